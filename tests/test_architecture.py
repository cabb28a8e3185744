"""docs/architecture.md's package picture is generated from the code and stays true."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]


def _package_graph() -> ModuleType:
    spec = importlib.util.spec_from_file_location("package_graph", ROOT / "tools/package_graph.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("package_graph", module)
    spec.loader.exec_module(module)
    return module


pg = _package_graph()


def test_plan_bridge_units_import_each_other_without_cycles() -> None:
    cycles = [c for c in pg.unit_cycles(pg.build()) if frozenset(c) not in pg.ALLOWED_CYCLES]
    assert cycles == []


def test_every_data_flow_arrow_names_a_type_the_consumer_imports_from_the_producer() -> None:
    assert pg.check_flows(pg.build()) == []


def test_architecture_doc_holds_the_generated_package_picture() -> None:
    current = (ROOT / "docs/architecture.md").read_text(encoding="utf-8")
    assert pg.render_doc(current, pg.mermaid(pg.build())) == current, (
        "docs/architecture.md is out of date: run python tools/package_graph.py --write"
    )


def test_cycle_detection_reports_a_cycle_between_two_units(tmp_path: Path) -> None:
    pkg = tmp_path / "plan_bridge"
    for sub, other in (("pddl", "planning"), ("planning", "pddl")):
        (pkg / sub).mkdir(parents=True)
        (pkg / sub / "__init__.py").write_text(f"from plan_bridge.{other} import thing\n")
    (pkg / "__init__.py").write_text("")
    assert pg.unit_cycles(pg.build(tmp_path)) == [["plan_bridge.pddl", "plan_bridge.planning"]]


def test_imports_under_type_checking_are_not_dependencies(tmp_path: Path) -> None:
    pkg = tmp_path / "plan_bridge"
    (pkg / "pddl").mkdir(parents=True)
    (pkg / "planning").mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "planning" / "__init__.py").write_text("from plan_bridge.pddl import Task\n")
    (pkg / "pddl" / "__init__.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from plan_bridge.planning import Plan\n"
        "class Task: ...\n"
    )
    graph = pg.build(tmp_path)
    assert graph.edges == {("plan_bridge.planning", "plan_bridge.pddl")}
    assert "Task" in graph.defines["plan_bridge.pddl"]


MODULE_LIMIT = 600


def test_a_module_over_600_lines_says_why_at_its_top() -> None:
    # The reason sits in the module docstring as "(Over 600 lines: why ...)".
    import ast

    unexplained = []
    for path in sorted((ROOT / "src").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if text.count("\n") <= MODULE_LIMIT:
            continue
        doc = ast.get_docstring(ast.parse(text)) or ""
        if "over 600 lines:" not in " ".join(doc.lower().split()):
            unexplained.append(f"{path.relative_to(ROOT)} ({text.count(chr(10))} lines)")
    assert unexplained == [], "split these or say why at the top: " + ", ".join(unexplained)


# -- the smach core ---------------------------------------------------------------------------
def _smach_core_imports(src: Path) -> dict[str, set[str]]:
    """``{core module: smach modules it imports}`` for every ``smach/*.py`` but the facade.

    Every import counts, also those under ``TYPE_CHECKING`` and inside functions.
    ``import smach`` (the facade, for the replaceable loggers and shutdown check) is
    not an edge; ``from smach import worker_pool`` is one to ``smach.worker_pool``.
    """
    import ast

    core = {p.stem for p in (src / "smach").glob("*.py") if p.stem != "__init__"}
    graph: dict[str, set[str]] = {}
    for name in sorted(core):
        tree = ast.parse((src / "smach" / f"{name}.py").read_text(encoding="utf-8"))
        targets: set[str] = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                if node.module == "smach":
                    targets |= {f"smach.{a.name}" for a in node.names if a.name in core}
                elif node.module.startswith("smach."):
                    targets.add(node.module)
            elif isinstance(node, ast.Import):
                targets |= {a.name for a in node.names if a.name.startswith("smach.")}
        graph[f"smach.{name}"] = targets
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import cycle of ``graph`` (``[a, b, ..., a]``), or ``[]`` if it has none."""
    state: dict[str, int] = {}  # 1 on the current path, 2 done
    path: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            if nxt in graph and nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        path.pop()
        state[node] = 2
        return []

    for start in sorted(graph):
        if start not in state:
            found = visit(start)
            if found:
                return found
    return []


def test_smach_core_modules_import_each_other_without_cycles_counting_type_only_imports() -> None:
    assert _cycle(_smach_core_imports(ROOT / "src")) == []


def test_no_smach_core_module_imports_introspection_or_ros() -> None:
    outward = {
        module: sorted(t for t in targets if t.startswith(("smach.introspection", "smach.ros")))
        for module, targets in _smach_core_imports(ROOT / "src").items()
    }
    assert {m: t for m, t in outward.items() if t} == {}


def test_the_core_cycle_check_finds_a_cycle_made_only_of_type_checking_imports(
    tmp_path: Path,
) -> None:
    pkg = tmp_path / "smach"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "state.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from smach.container import C\n"
    )
    (pkg / "container.py").write_text("from smach.state import State\n")
    (pkg / "leaf.py").write_text("import smach\nfrom smach import state\n")
    graph = _smach_core_imports(tmp_path)
    assert graph["smach.leaf"] == {"smach.state"}
    assert _cycle(graph) == ["smach.container", "smach.state", "smach.container"]
