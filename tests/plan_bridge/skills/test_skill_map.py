"""Skill maps (skills.toml): PDDL actions bound to the user's skill factories."""

from __future__ import annotations

import pickle
import shutil
import sys
import textwrap
from pathlib import Path

import pytest

import smach
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.missions.mission import load_target
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import SkillRegistry
from plan_bridge.skills.skill_map import SkillMap, SkillMapError, load_skill_map
from plan_bridge.skills.skill_map_model import SelectedArguments

COURIER = Path(__file__).parents[1] / "data" / "courier"
DRIVE = PlanStep("drive", ("rover", "lab", "store"))
GRAB = PlanStep("grab", ("rover", "box", "store"))


@pytest.fixture(scope="module")
def task() -> PlanningTask:
    return load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A fresh copy of the courier domain folder (PDDL and courier_skills.py)."""
    target = tmp_path / "courier"
    shutil.copytree(COURIER, target, ignore=shutil.ignore_patterns("__pycache__", "*.log"))
    return target


def write(folder: Path, name: str, text: str) -> Path:
    """Write ``text`` (dedented; its first line is line 1) to ``folder/name``."""
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
    return path


def map_error(path: Path, task: PlanningTask) -> str:
    with pytest.raises(SkillMapError) as info:
        load_skill_map(path, task)
    return str(info.value)


def test_a_map_entry_registers_the_users_skill_with_its_outcome_map(
    folder: Path, task: PlanningTask
) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        outcome_map = { arrived = "succeeded", blocked = "aborted" }
        """,
    )
    skill_map = load_skill_map(path, task)
    registry = skill_map.apply(SkillRegistry())
    skill = registry.get("drive")
    assert skill is not None
    assert skill.outcome_map == {"arrived": "succeeded", "blocked": "aborted"}
    assert skill.simulated is False  # the user's own skill: the world adopts its effects
    state, _ = registry.create(DRIVE)
    assert type(state).__name__ == "Drive"
    assert (getattr(state, "robot", None), getattr(state, "to", None)) == ("rover", "store")
    entry = skill_map.entry("drive")
    assert entry is not None and entry.line == 1 and entry.location == f"{path}:1"


def test_a_mapped_skill_passes_the_registry_check_and_other_actions_stay_simulated(
    folder: Path, task: PlanningTask
) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        outcome_map = { arrived = "succeeded", blocked = "aborted" }
        """,
    )
    registry = symbolic_skills(SimulatedWorld(task))
    load_skill_map(path, task).apply(registry)
    assert registry.check(task) == []
    assert registry.actions == ["drive"]
    state, skill = registry.create(GRAB)
    assert skill is None and type(state).__name__ == "SymbolicSkill"


def test_arguments_choose_parameters_in_any_order_and_pass_constants_as_written(
    folder: Path, task: PlanningTask
) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [grab]
        factory = "courier_skills:Grab"
        arguments = ["?x", "?P", "firm", 2, 0.5, true]
        """,
    )
    registry = load_skill_map(path, task).apply(SkillRegistry())
    skill = registry.get("grab")
    assert skill is not None and isinstance(skill.factory, SelectedArguments)
    assert skill.arity_problem(3) is None and skill.arity_problem(2) is not None
    state, _ = registry.create(GRAB)
    assert getattr(state, "received", None) == ("store", "box", "firm", 2, 0.5, True)


def test_without_arguments_the_factory_gets_every_parameter_in_pddl_order(
    folder: Path, task: PlanningTask
) -> None:
    path = write(folder, "skills.toml", 'grab = "courier_skills:Grab"\n')
    registry = load_skill_map(path, task).apply(SkillRegistry())
    state, _ = registry.create(GRAB)
    assert getattr(state, "received", None) == ("rover", "box", "store")


def test_array_entries_give_an_action_a_main_skill_and_variants(
    folder: Path, task: PlanningTask
) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [[grab]]
        factory = "courier_skills:Grab"

        [[grab]]
        factory = "courier_skills:make_gentle_grab"
        variant = "gentle"
        """,
    )
    skill_map = load_skill_map(path, task)
    registry = skill_map.apply(SkillRegistry())
    assert registry.variants("grab") == ("gentle",)
    state, skill = registry.create(GRAB, "gentle")
    assert getattr(state, "received", None) == ("gentle", "rover", "box", "store")
    assert skill is not None and skill.simulated is False
    gentle = skill_map.entry("grab", "gentle")
    assert gentle is not None and gentle.line == 4


def test_a_module_in_the_map_folder_imports_its_siblings_relatively(
    folder: Path, task: PlanningTask
) -> None:
    write(
        folder,
        "careful.py",
        """
        from .courier_skills import Grab


        def careful_grab(robot, parcel, room):
            return Grab("careful", parcel)
        """,
    )
    path = write(folder, "skills.toml", 'grab = "careful:careful_grab"\n')
    registry = load_skill_map(path, task).apply(SkillRegistry())
    state, _ = registry.create(GRAB)
    assert getattr(state, "received", None) == ("careful", "box")


def test_an_installed_module_is_found_when_the_folder_has_none_of_that_name(
    folder: Path, task: PlanningTask, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    site = tmp_path / "site"
    site.mkdir()
    write(
        site,
        "courier_robot_driver.py",
        """
        from smach.testing import ScriptedState


        def drive(robot, to):
            return ScriptedState(["succeeded"], outcomes=["succeeded", "aborted", "preempted"])
        """,
    )
    monkeypatch.syspath_prepend(str(site))
    path = write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_robot_driver:drive"
        arguments = ["?r", "?to"]
        """,
    )
    try:
        registry = load_skill_map(path, task).apply(SkillRegistry())
        state, skill = registry.create(DRIVE)
        assert skill is not None and state.get_registered_outcomes()
    finally:
        sys.modules.pop("courier_robot_driver", None)


ERRORS = [
    pytest.param(
        """
        [drve]
        factory = "courier_skills:Drive"
        """,
        1,
        ["the domain has no action 'drve'", "did you mean drive?", "actions: drive, grab"],
        id="unknown-action",
    ),
    pytest.param(
        """
        # the courier's skills
        [drive]
        factory = "courier_skill:Drive"
        """,
        3,
        ["no module 'courier_skill'", "did you mean courier_skills?", "installed module"],
        id="module-not-found",
    ),
    pytest.param(
        """
        [drive]
        arguments = ["?r", "?to"]
        factory = "courier_skills:Drvie"
        """,
        3,
        [
            "has no attribute 'Drvie'",
            "did you mean Drive?",
            "callables in it: Drive, Grab, make_gentle_grab",  # defined there, not imported
        ],
        id="attribute-missing",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:SPEED"
        """,
        2,
        ["courier_skills:SPEED is 0.5 (a number), which is not callable", "returns a smach.State"],
        id="not-callable",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?to"]
        """,
        2,
        ["cannot take 1 argument(s)", 'arguments = ["?to"]', "missing a required argument"],
        id="too-few-selected-arguments",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        """,
        2,
        ["cannot take the action's 3 parameter(s) (?r, ?from, ?to)", "arguments = ["],
        id="factory-arity-without-arguments",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?dest"]
        """,
        3,
        ["?dest is not a parameter of drive", "parameters: ?r, ?from, ?to"],
        id="parameter-not-of-the-action",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "to"]
        """,
        3,
        ["'to' is written like the parameter ?to without its '?'", 'write "?to"'],
        id="parameter-without-question-mark",
    ),
    pytest.param(
        """
        [grab]
        factroy = "courier_skills:Grab"
        """,
        2,
        ["unknown key 'factroy'", "did you mean factory?", "allowed keys: factory, arguments"],
        id="unknown-key",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        grab = "courier_skills:Grab"
        """,
        4,
        ["unknown key 'grab'", "'grab' is an action", "before the first [table]"],
        id="short-entry-after-a-table",
    ),
    pytest.param(
        """
        [grab]
        factory = "courier_skills:Grab"
        outcome_map = { dropped = "failed" }
        """,
        3,
        ["outcome_map sends 'dropped' to \"failed\";", "succeeded, aborted, preempted"],
        id="outcome-map-target",
    ),
    pytest.param(
        """
        [grab]
        factory = "courier_skills:Grab"

        [grab.outcome_map]
        dropped = "succeded"
        """,
        4,
        ["did you mean succeeded?"],
        id="outcome-map-subtable-typo",
    ),
    pytest.param(
        """
        [grab]
        outcome_map = { dropped = "aborted" }
        """,
        1,
        ['no factory; add factory = "module:callable"'],
        id="no-factory",
    ),
    pytest.param(
        """
        [grab]
        factory = "courier_skills.Grab"
        """,
        2,
        ['is not "module:callable"', 'e.g. factory = "courier_skills:Grab"'],
        id="factory-without-colon",
    ),
    pytest.param(
        """
        [grab]
        factory = "courier_skills:Grab"
        variant = ""
        """,
        3,
        ["variant must be a non-empty string"],
        id="empty-variant",
    ),
    pytest.param(
        """
        [[grab]]
        factory = "courier_skills:Grab"
        [[grab]]
        factory = "courier_skills:make_gentle_grab"
        """,
        3,
        ["a second main skill (no variant) for 'grab' (the first is at line 1)", "variant ="],
        id="two-main-skills",
    ),
    pytest.param(
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"
        """,
        3,
        ["invalid TOML: Unclosed array at the end of the file"],
        id="toml-unclosed-at-end",
    ),
    pytest.param(
        """
        [drive]
        factory = courier_skills:Drive
        """,
        "2:11",
        ["invalid TOML: Invalid value", "text needs quotes"],
        id="toml-syntax-with-column",
    ),
    pytest.param(
        """
        [grab]
        factory = "courier_skills:Grab"

        [grab]
        factory = "courier_skills:make_gentle_grab"
        """,
        4,
        ["invalid TOML:", "[[action]] entries with variant"],
        id="same-table-twice",
    ),
    pytest.param(
        """
        drive = 3
        """,
        1,
        ["an entry is a table", 'drive = "module:callable"'],
        id="entry-not-a-table",
    ),
]


@pytest.mark.parametrize(("text", "line", "fragments"), ERRORS)
def test_each_mistake_in_a_map_is_reported_at_its_line_with_what_is_allowed(
    folder: Path, task: PlanningTask, text: str, line: int | str, fragments: list[str]
) -> None:
    path = write(folder, "skills.toml", text)
    message = map_error(path, task)
    assert message.startswith(f"{path}:{line}:"), message
    for fragment in fragments:
        assert fragment in message, message
    assert "Traceback" not in message


def test_a_module_that_fails_to_import_is_reported_with_its_error(
    folder: Path, task: PlanningTask
) -> None:
    write(folder, "broken.py", 'raise RuntimeError("no robot connected")\n')
    path = write(folder, "skills.toml", '# robot drivers\ngrab = "broken:make_grab"\n')
    message = map_error(path, task)
    assert message.startswith(f"{path}:2: [grab]: factory broken:make_grab: importing ")
    assert "broken.py failed: RuntimeError: no robot connected" in message


def test_every_problem_of_a_map_is_reported_at_once(folder: Path, task: PlanningTask) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?where"]

        [grab]
        factory = "courier_skills:Grab"
        outcome_map = { dropped = "lost" }
        """,
    )
    with pytest.raises(SkillMapError) as info:
        load_skill_map(path, task)
    assert [(p.line, p.path) for p in info.value.problems] == [(3, str(path)), (7, str(path))]
    assert str(info.value).startswith(f"2 problems in the skill map {path}:\n  {path}:3: ")


def test_a_skill_map_error_survives_pickling(folder: Path, task: PlanningTask) -> None:
    path = write(folder, "skills.toml", 'fly = "courier_skills:Drive"\n')
    with pytest.raises(SkillMapError) as info:
        load_skill_map(path, task)
    copy = pickle.loads(pickle.dumps(info.value))
    assert str(copy) == str(info.value) and copy.line == 1


def test_applying_a_map_over_an_action_already_registered_names_both(
    folder: Path, task: PlanningTask
) -> None:
    path = write(folder, "skills.toml", 'grab = "courier_skills:Grab"\n')
    registry = SkillRegistry()

    def hand_written_grab(robot: str, parcel: str, room: str) -> smach.State:
        raise AssertionError("never built")

    registry.add("grab", hand_written_grab)
    with pytest.raises(SkillMapError) as info:
        load_skill_map(path, task).apply(registry, registered_by="the test's setup")
    message = str(info.value)
    assert message.startswith(f"{path}:1: [grab] maps it to courier_skills:Grab")
    assert "the test's setup already registered a skill for 'grab'" in message
    assert "hand_written_grab" in message
    registry_skill = registry.get("grab")
    assert registry_skill is not None and registry_skill.factory is hand_written_grab


def test_applying_the_same_map_again_changes_nothing(folder: Path, task: PlanningTask) -> None:
    path = write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        """,
    )
    registry = load_skill_map(path, task).apply(SkillRegistry())
    first = registry.get("drive")
    # A domain setup() that returns the same registry on every call (a study's runs).
    load_skill_map(path, task).apply(registry, registered_by="the domain's setup()")
    assert registry.get("drive") is first


SETUP = """
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.skills.registry import SkillRegistry

from .courier_skills import Grab


def setup(task, *, seed, fail_rate):
    world = SimulatedWorld(task, seed=seed, fail_rate=fail_rate)
    skills = SkillRegistry()
    skills.add("grab", Grab)
    return MissionSetup(skills=symbolic_skills(world, skills), world=world)
"""


def test_target_setup_applies_the_folder_map_over_symbolic_skills(folder: Path) -> None:
    write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        outcome_map = { arrived = "succeeded", blocked = "aborted" }
        """,
    )
    target = load_target(folder)
    setup = target.setup(seed=0, fail_rate=0.0)
    assert setup.skills.actions == ["drive"]
    assert setup.skills.fallback is not None
    assert isinstance(setup.extra["skill_map"], SkillMap)
    assert setup.skills.check(target.task) == []


def test_target_setup_adds_the_map_to_the_skills_of_the_domain_setup(folder: Path) -> None:
    write(folder, "__init__.py", SETUP)
    write(
        folder,
        "skills.toml",
        """
        [drive]
        factory = "courier_skills:Drive"
        arguments = ["?r", "?to"]
        outcome_map = { arrived = "succeeded" }

        [[grab]]
        factory = "courier_skills:make_gentle_grab"
        variant = "gentle"
        """,
    )
    target = load_target(folder)
    setup = target.setup(seed=0, fail_rate=0.0)
    assert setup.skills.actions == ["drive", "grab"]
    assert setup.skills.variants("grab") == ("gentle",)
    # The map's modules are the domain package's: one courier_skills, not two.
    assert target.module is not None
    own = sys.modules[f"{target.module.__name__}.courier_skills"]
    grab = setup.skills.get("grab")
    assert grab is not None and grab.factory is own.Grab


def test_a_map_entry_for_an_action_the_domain_setup_registered_names_both(
    folder: Path,
) -> None:
    write(folder, "__init__.py", SETUP)
    path = write(
        folder, "skills.toml", '# gentler\n[grab]\nfactory = "courier_skills:make_gentle_grab"\n'
    )
    target = load_target(folder)
    with pytest.raises(SkillMapError) as info:
        target.setup(seed=0, fail_rate=0.0)
    message = str(info.value)
    assert message.startswith(f"{path}:2: [grab] maps it to courier_skills:make_gentle_grab")
    assert "the domain's setup() (" in message and "__init__.py" in message
    assert "courier_skills:Grab" in message
