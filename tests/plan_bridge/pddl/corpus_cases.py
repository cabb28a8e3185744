"""Reading the front end's corpus (``corpus/``): each case states its expected verdict.

A case file begins with ``;; key: value`` lines (``verdict``, ``line``, ``message``,
``pair``, ``plan``, ``unless-installed``, ...). A ``domain-*.pddl`` case is read with
``base/problem.pddl`` and a ``problem-*.pddl`` case with ``base/domain.pddl``, unless
``;; pair:`` names another file of ``base``. Used by the corpus test,
``benchmarks/front_end_corpus.py`` and ``tools/front_end_agreement.py``.
"""

from __future__ import annotations

from pathlib import Path

CORPUS = Path(__file__).parent / "corpus"


def expectations(path: Path) -> dict[str, str]:
    """The case's ``;; key: value`` header lines, as a mapping."""
    found: dict[str, str] = {}
    for row in path.read_text("utf-8", "replace").lstrip("\ufeff").splitlines():
        if not row.startswith(";; "):
            break
        key, _, value = row[3:].partition(": ")
        found[key] = value
    return found


def pair(path: Path, meta: dict[str, str]) -> tuple[Path, Path]:
    """(domain, problem): the case and the base file it is read with."""
    kind = path.name.split("-", 1)[0]
    default = "problem.pddl" if kind == "domain" else "domain.pddl"
    other = path.parent / "base" / meta.get("pair", default)
    return (path, other) if kind == "domain" else (other, path)
