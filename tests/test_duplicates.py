"""No block of code in src/ is written twice (issue 38).

A copy is a run of 6 or more identical lines at two places: lines compared with their
white space folded; blank lines, comments, docstrings and import statements left out
(prose, and the names a module uses, are no logic). Same-shape declarations kept
on purpose are listed in :data:`KEPT_DECLARATIONS`, each with its reason (and in
docs/architecture.md, "Same-shape declarations we keep"); every other copy fails the
first test. The list only shrinks: a listed declaration that is gone fails the second
test. An entry is the two files (sorted) and the first line of the copy, white space
folded.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
MIN_LINES = 6
SUFFIXES = (".py", ".js", ".css", ".html")

Key = tuple[str, str, str]

#: Same-shape declarations we keep: sharing them would hide a signature from readers
#: and from mypy.
KEPT_DECLARATIONS: dict[Key, str] = {
    ("plan_bridge/planning/types.py", "plan_bridge/planning/types.py", "def solve("): (
        "CancellablePlanner.solve is Planner.solve with cancel: a protocol extends another"
    ),
    ("plan_bridge/planning/portfolio.py", "plan_bridge/planning/types.py", "def solve("): (
        "PlannerPortfolio.solve implements the Planner protocols' solve"
    ),
    ("plan_bridge/fleet/planner.py", "plan_bridge/planning/types.py", "def solve("): (
        "FleetPlanner.solve implements the Planner protocols' solve"
    ),
    ("plan_bridge/fleet/planner.py", "plan_bridge/planning/portfolio.py", "def solve("): (
        "both implement the Planner protocols' solve"
    ),
    ("plan_bridge/planning/engines.py", "plan_bridge/planning/up_planner.py", "def solve("): (
        "AutoPlanner.solve and UPPlanner.solve: the planners' solve with cancel and values"
    ),
    (
        "plan_bridge/planning/engines.py",
        "plan_bridge/planning/up_planner.py",
        "def _interpret(",
    ): "WarmPlanner._interpret overrides UPPlanner._interpret",
    ("smach/container.py", "smach/wrapper.py", "def __init__("): (
        "the original SMACH's positional signature (outcomes, input_keys, output_keys)"
    ),
    ("smach/machine_runs.py", "smach/machine_runs.py", "self,"): (
        "_end_loop and _leave_inline end a machine's loop from the same arguments"
    ),
    ("smach/user_data.py", "smach/user_data.py", "remapping: Mapping[str, str] | None = None,"): (
        "make_remapper takes what Remapper's constructor takes"
    ),
    ("smach/events.py", "smach/introspection/events.py", "__all__ = ["): (
        "smach.introspection.events re-exports smach.events' names where user code imports them"
    ),
    ("plan_bridge/missions/mission.py", "plan_bridge/missions/target.py", "if TYPE_CHECKING:"): (
        "plan_bridge.missions.mission re-exports target's names where domain folders import them"
    ),
}


@dataclass(frozen=True)
class Copy:
    """A run of ``length`` identical lines at ``first``:``first_line`` and at ``second``:``second_line``."""

    first: str
    first_line: int
    second: str
    second_line: int
    length: int
    text: str
    """Its first line, white space folded."""

    @property
    def key(self) -> Key:
        first, second = sorted((self.first, self.second))
        return (first, second, self.text)

    def __str__(self) -> str:
        return (
            f"{self.first}:{self.first_line} ~ {self.second}:{self.second_line} "
            f"({self.length} lines from {self.text!r})"
        )


def _left_out(text: str) -> set[int]:
    """The line numbers of a Python module's import statements and docstrings."""
    lines: set[int] = set()
    for node in ast.walk(ast.parse(text)):
        spans: list[ast.stmt] = []
        if isinstance(node, ast.Import | ast.ImportFrom):
            spans.append(node)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            first = node.body[0] if node.body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                spans.append(first)
        for span in spans:
            lines.update(range(span.lineno, (span.end_lineno or span.lineno) + 1))
    return lines


def code_lines(path: Path) -> list[tuple[int, str]]:
    """``(line number, text with white space folded)`` of every line that counts."""
    text = path.read_text(encoding="utf-8")
    left_out = _left_out(text) if path.suffix == ".py" else set()
    comment = "#" if path.suffix == ".py" else "//"
    kept = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = " ".join(raw.split())
        if line and not line.startswith(comment) and number not in left_out:
            kept.append((number, line))
    return kept


def find_copies(src: Path, min_lines: int = MIN_LINES) -> list[Copy]:
    """Every pair of places under ``src`` sharing ``min_lines`` or more identical lines,
    each run as long as it goes (two places in one file do not overlap)."""
    files = {
        path.relative_to(src).as_posix(): code_lines(path)
        for path in sorted(src.rglob("*"))
        if path.suffix in SUFFIXES and path.is_file()
    }
    texts = {name: [line for _, line in lines] for name, lines in files.items()}
    places: dict[tuple[str, ...], list[tuple[str, int]]] = {}
    for name, lines in texts.items():
        for start in range(len(lines) - min_lines + 1):
            places.setdefault(tuple(lines[start : start + min_lines]), []).append((name, start))
    copies = []
    for found in places.values():
        for n, (first, i) in enumerate(found):
            for second, j in found[n + 1 :]:
                a, b = texts[first], texts[second]
                if i and j and a[i - 1] == b[j - 1] and (first != second or i < j - 1):
                    continue  # inside a longer run, reported from its start
                length = 0
                while (
                    i + length < len(a)
                    and j + length < len(b)
                    and a[i + length] == b[j + length]
                    and (first != second or i + length < j)
                ):
                    length += 1
                if length >= min_lines:
                    copies.append(
                        Copy(first, files[first][i][0], second, files[second][j][0], length, a[i])
                    )
    return sorted(copies, key=lambda c: (c.first, c.first_line, c.second, c.second_line))


def test_src_has_no_copy_of_six_lines_or_more_but_the_kept_declarations() -> None:
    unlisted = [str(c) for c in find_copies(SRC) if c.key not in KEPT_DECLARATIONS]
    assert unlisted == [], "share these (or, for a declaration, list it and say why)"


def test_every_kept_declaration_still_exists() -> None:
    found = {c.key for c in find_copies(SRC)}
    gone = sorted(KEPT_DECLARATIONS.keys() - found)
    assert gone == [], f"remove these from KEPT_DECLARATIONS: {gone}"


def test_a_copy_is_found_across_files_and_in_one_file_with_its_whole_length(
    tmp_path: Path,
) -> None:
    block = "".join(f"    total += {n} * x  # step {n}\n" for n in range(7))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text(
        f"def f(x):\n    total = 0\n{block}    return total\n\n\ndef g(x):\n    total = 1\n{block}"
    )
    (tmp_path / "pkg" / "b.py").write_text(
        "import os\n\n\ndef h(x):\n    total = 2\n\n    # a comment\n    if x:\n"
        + block.replace("    ", "        ")
    )
    copies = find_copies(tmp_path)
    assert [(c.first, c.first_line, c.second, c.second_line, c.length) for c in copies] == [
        ("pkg/a.py", 3, "pkg/a.py", 15, 7),
        ("pkg/a.py", 3, "pkg/b.py", 9, 7),
        ("pkg/a.py", 15, "pkg/b.py", 9, 7),
    ]
    assert copies[0].text == "total += 0 * x # step 0"


def test_blank_lines_comments_docstrings_imports_and_runs_under_six_lines_are_no_copy(
    tmp_path: Path,
) -> None:
    imports = (
        "from collections import (\n    OrderedDict,\n    deque,\n    Counter,\n)\nimport os\n"
    )
    doc = '"""One.\n\nTwo.\nThree.\nFour.\nFive.\nSix.\n"""\n'
    five = "".join(f"y = {n}\n" for n in range(5))
    (tmp_path / "a.py").write_text(doc + imports + five + "\n# one\n# two\n\n\n")
    (tmp_path / "b.py").write_text(doc + imports + five + "z = 1\n# one\n# two\n")
    assert find_copies(tmp_path) == []
    (tmp_path / "c.py").write_text(five + "z = 1\n")
    assert [(c.first, c.second, c.length) for c in find_copies(tmp_path)] == [("b.py", "c.py", 6)]
