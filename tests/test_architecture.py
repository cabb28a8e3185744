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


# -- import circles between files --------------------------------------------------------------
def test_no_two_files_import_each_other() -> None:
    # Every import counts: under TYPE_CHECKING and inside functions too. Two files that
    # need each other share a third file, or one receives what it needs (a protocol).
    assert pg.file_cycles() == []


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path


def test_an_import_inside_a_function_closes_a_circle(tmp_path: Path) -> None:
    src = _package(
        tmp_path,
        {
            "plan_bridge/__init__.py": "",
            "plan_bridge/pddl/__init__.py": "",
            "plan_bridge/pddl/a.py": "from plan_bridge.pddl.b import B\n",
            "plan_bridge/pddl/b.py": (
                "class B: ...\ndef late():\n    from plan_bridge.pddl import a\n    return a\n"
            ),
        },
    )
    assert pg.file_cycles(src) == [["plan_bridge.pddl.a", "plan_bridge.pddl.b"]]


def test_an_import_under_type_checking_closes_a_circle(tmp_path: Path) -> None:
    src = _package(
        tmp_path,
        {
            "smach/__init__.py": "",
            "smach/state.py": (
                "from typing import TYPE_CHECKING\n"
                "if TYPE_CHECKING:\n"
                "    from smach.container import Container\n"
            ),
            "smach/container.py": "from .state import State\n",
        },
    )
    assert pg.file_cycles(src) == [["smach.container", "smach.state"]]


def test_a_circle_through_a_package_facade_and_round_three_files_is_found(
    tmp_path: Path,
) -> None:
    # ``import smach`` in a module the facade imports is a circle; a module's own
    # package is not an edge, and a chain without a way back is no circle.
    src = _package(
        tmp_path,
        {
            "smach/__init__.py": "from smach.state import State\n",
            "smach/state.py": "import smach\n",
            "smach/leaf.py": "from smach import state\n",
            "plan_bridge/__init__.py": "",
            "plan_bridge/x.py": "from plan_bridge import y\n",
            "plan_bridge/y.py": "import plan_bridge.z\n",
            "plan_bridge/z.py": "from plan_bridge.x import X\n",
        },
    )
    assert pg.file_imports(src)["smach.leaf"] == {"smach.state"}
    assert pg.file_cycles(src) == [
        ["plan_bridge.x", "plan_bridge.y", "plan_bridge.z"],
        ["smach", "smach.state"],
    ]


# -- the smach core ---------------------------------------------------------------------------
def test_no_smach_core_module_imports_introspection_or_ros() -> None:
    # The core: the files smach/*.py but the package's __init__. Every import counts.
    core = {f"smach.{p.stem}" for p in (ROOT / "src/smach").glob("*.py") if p.stem != "__init__"}
    outward = {
        module: sorted(t for t in targets if t.startswith(("smach.introspection", "smach.ros")))
        for module, targets in pg.file_imports().items()
        if module in core
    }
    assert {m: t for m, t in outward.items() if t} == {}


def test_plan_bridge_imports_no_private_module_of_smach() -> None:
    # rclpy's names come from smach.ros.rclpy_api, not smach.ros._api (issue 38).
    private = {
        module: sorted(t for t in targets if t.startswith("smach") and "._" in t)
        for module, targets in pg.file_imports().items()
        if module.startswith("plan_bridge")
    }
    assert {m: t for m, t in private.items() if t} == {}
