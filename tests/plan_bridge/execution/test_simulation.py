"""The simulated world's helpers for domain worlds: fault draws, facts, variants."""

from __future__ import annotations

import ast
import copy
import json
import random
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.execution.snapshots import SnapshotError
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.skills.ros.entries import runs_on_ros

ROOMS = Path(__file__).parents[1] / "data" / "rooms"


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


class FaultyWorld(SimulatedWorld):
    fault_scale = {"slip": 2.0, "never": 0.0, "sure": 50.0}
    variants = ("", "dark")


def test_chance_happens_with_probability_fail_rate_times_the_scale_of_the_kind() -> None:
    world = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    draws = [world.chance("slip") for _ in range(4000)]
    assert 0.37 < sum(draws) / len(draws) < 0.43  # 0.2 x 2.0
    assert all(world.chance("sure") for _ in range(100))  # capped at 1


def test_chance_is_seeded_and_draws_nothing_where_a_fault_cannot_happen() -> None:
    first = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    second = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    assert [first.chance("slip") for _ in range(50)] == [second.chance("slip") for _ in range(50)]
    state = first.rng.getstate()
    assert not first.chance("never")
    assert not FaultyWorld(rooms(), seed=3, fail_rate=0.0).chance("slip")
    assert first.rng.getstate() == state
    with pytest.raises(KeyError):
        first.chance("unknown")


def test_chance_draws_from_the_generator_it_is_given() -> None:
    world = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    own, state = random.Random(7), world.rng.getstate()
    expected = random.Random(7).random() < 0.4
    assert world.chance("slip", own) == expected
    assert world.rng.getstate() == state
    assert own.getstate() != random.Random(7).getstate()


def test_holds_tells_whether_a_fact_is_true_in_the_world() -> None:
    world = SimulatedWorld(rooms())
    assert world.holds("at", "robot1", "hall")
    assert not world.holds("at", "robot1", "office")


def test_a_world_knows_its_variants_and_refuses_others() -> None:
    assert FaultyWorld(rooms(), variant="dark").variant == "dark"
    assert SimulatedWorld(rooms()).variant == ""
    with pytest.raises(ValueError, match="unknown variant 'dim'; variants: , dark"):
        FaultyWorld(rooms(), variant="dim")
    with pytest.raises(ValueError, match="unknown variant 'dark'"):
        SimulatedWorld(rooms(), variant="dark")


# -- snapshots: a world declares its state once, snapshot/restore cover all of it -------------

DOMAINS = Path(__file__).parents[3] / "domains"
# Every mission folder in domains/ (each has a simulated world): a new one is checked
# without editing this file.
# (Not the folders whose skills.toml binds actions to ROS 2: they need a robot running.)
WITH_WORLDS = tuple(
    sorted(
        d.name for d in DOMAINS.iterdir() if (d / "domain.pddl").is_file() and not runs_on_ros(d)
    )
)
# Their plans run step by step (the restore test below); temporal missions dispatch a
# timeline and are resumed through it (tests/plan_bridge/cli/test_crash_resume.py).
SHIPPED = tuple(
    d for d in WITH_WORLDS if ":durative-actions" not in (DOMAINS / d / "domain.pddl").read_text()
)


def shipped_world(domain: str, seed: int = 1, fail_rate: float = 0.3) -> Any:
    from plan_bridge.missions.mission import load_target

    target = load_target(str(DOMAINS / domain), None)
    return target, target.setup(seed=seed, fail_rate=fail_rate)


def all_world_classes() -> list[type[SimulatedWorld]]:
    """Every subclass of SimulatedWorld loaded so far (shipped domains included)."""
    for domain in WITH_WORLDS:
        shipped_world(domain)
    found: list[type[SimulatedWorld]] = []
    stack = [SimulatedWorld]
    while stack:
        cls = stack.pop()
        found.append(cls)
        stack.extend(cls.__subclasses__())
    return found


def test_every_world_class_declares_each_of_its_attributes_once() -> None:
    checked = []
    for cls in all_world_classes():
        kinds = [cls.declared(k) for k in ("state", "constant", "wiring")]
        names = [n for names in kinds for n in names]
        assert len(names) == len(set(names)), f"{cls.__qualname__}: declared twice: {names}"
        checked.append(cls.__qualname__)
    assert {"DoorWorld", "TableWorld", "RechargeWorld", "FaultyWorld"} <= set(checked)


@pytest.mark.parametrize("domain", WITH_WORLDS)
def test_a_shipped_world_has_no_attribute_outside_its_declarations(domain: str) -> None:
    _, setup = shipped_world(domain)
    assert setup.world.undeclared() == []
    assert json.loads(json.dumps(setup.world.snapshot())) == setup.world.snapshot()


def test_a_test_world_has_no_attribute_outside_its_declarations() -> None:
    world = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    assert world.undeclared() == []


def world_classes_in_source() -> list[tuple[Path, ast.ClassDef]]:
    """Every class in domains/ and tests/ with a base named ``...World`` (worlds defined
    inside functions too, which no import finds)."""
    found = []
    for folder in (DOMAINS, Path(__file__).parents[2]):
        for path in sorted(folder.rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.ClassDef) and any(
                    (base.id if isinstance(base, ast.Name) else getattr(base, "attr", "")).endswith(
                        "World"
                    )
                    for base in node.bases
                ):
                    found.append((path, node))
    return found


def declared_in(node: ast.ClassDef) -> set[str]:
    """The names a class body lists in its own state/constant/wiring tuples."""
    names: set[str] = set()
    for statement in node.body:
        target = statement.target if isinstance(statement, ast.AnnAssign) else (
            statement.targets[0] if isinstance(statement, ast.Assign) else None
        )  # fmt: skip
        value = getattr(statement, "value", None)
        kind = target.id if isinstance(target, ast.Name) else ""
        if kind in ("state", "constant", "wiring") and isinstance(value, ast.Tuple):
            names.update(e.value for e in value.elts if isinstance(e, ast.Constant))
    return names


def writes_in(node: ast.ClassDef) -> tuple[set[str], list[str]]:
    """Attributes the class's methods set on ``self``, and any they set on a class."""
    on_self: set[str] = set()
    on_class: list[str] = []
    for sub in ast.walk(node):
        targets: list[ast.expr] = []
        if isinstance(sub, ast.Assign):
            targets = list(sub.targets)
        elif isinstance(sub, (ast.AugAssign, ast.AnnAssign)):
            targets = [sub.target]
        for target in targets:
            if isinstance(target, ast.Attribute) and isinstance(target.value, ast.Name):
                if target.value.id == "self":
                    on_self.add(target.attr)
                elif target.value.id in (node.name, "cls"):
                    on_class.append(f"{target.value.id}.{target.attr}")
            elif isinstance(target, ast.Attribute) and isinstance(target.value, ast.Call):
                on_class.append(f"type(...).{target.attr}")
    return on_self, on_class


def test_every_world_in_the_domains_and_the_tests_declares_what_it_sets() -> None:
    """A world class anywhere (shipped, or in a test, even inside a function) declares
    each attribute its methods set, and keeps no state on a class (a snapshot would
    miss it)."""
    from plan_bridge.execution.timed_world import TimedWorld

    classes = world_classes_in_source()
    own = {node.name: declared_in(node) | {"state", "constant", "wiring"} for _, node in classes}
    parents = {node.name: [getattr(b, "id", getattr(b, "attr", "")) for b in node.bases]
               for _, node in classes}  # fmt: skip

    def inherited(name: str) -> set[str]:
        return own.get(name, set()).union(*(inherited(p) for p in parents.get(name, [])))

    base = {*TimedWorld.declared("state"), *TimedWorld.declared("constant"),
            *TimedWorld.declared("wiring")}  # fmt: skip
    problems = []
    for path, node in classes:
        if node.name == "Forgetful":  # the test of the refusal below
            continue
        known = base | inherited(node.name)
        on_self, on_class = writes_in(node)
        problems += [f"{path.name}: {node.name}.{name} undeclared" for name in on_self - known]
        problems += [f"{path.name}: {node.name} sets {name}" for name in on_class]
    assert problems == []
    names = {node.name for _, node in classes}
    assert {"DoorWorld", "CourierWorld", "FaultyWorld", "World", "Forgetful"} <= names


def test_snapshot_refuses_a_world_with_an_undeclared_attribute() -> None:
    class Forgetful(SimulatedWorld):
        def __init__(self, task: PlanningTask) -> None:
            super().__init__(task)
            self.battery = 100.0

    with pytest.raises(SnapshotError, match=r"Forgetful: attribute\(s\) battery declared nowhere"):
        Forgetful(rooms()).snapshot()


def class_attributes(world: SimulatedWorld) -> dict[str, str]:
    """What the world's classes hold (repr: a list changed in place shows too)."""
    return {
        f"{klass.__qualname__}.{name}": repr(value)
        for klass in type(world).__mro__
        for name, value in vars(klass).items()
    }


@pytest.mark.timeout(120)
@pytest.mark.parametrize("domain", SHIPPED)
def test_a_world_restored_mid_mission_ends_as_the_world_that_was_never_stopped(
    domain: str,
) -> None:
    """Run a mission; save the world after each step; for some of those saves, restore
    a fresh world (another seed) and run the rest of the plan: the same end."""
    from plan_bridge.execution.executive import Executive
    from plan_bridge.planning.planner import get_planner

    target, setup = shipped_world(domain)
    saves: list[tuple[dict[str, Any], dict[str, Any]]] = []
    world = setup.world
    # The task and its model are shared, read-only objects; the rest is the world's own.
    own = [name for name in world.declared("constant") if name not in ("task", "model")]
    constants = {name: copy.deepcopy(getattr(world, name)) for name in own}
    executive = Executive(
        target.task, setup.skills, get_planner("fast-downward"), sense=setup.sense,
        concurrent=setup.concurrent,
        checkpoint=lambda state: saves.append((json.loads(json.dumps(state)), world.snapshot())),
    )  # fmt: skip
    classes = class_attributes(world)
    executive.execute()
    end = world.snapshot()
    assert saves
    # The world's state is on the instance (where snapshots see it), not on a class.
    assert class_attributes(world) == classes
    # Nothing declared constant changed while the world ran.
    assert {name: getattr(world, name) for name in own} == constants
    for state, saved in saves[:: max(1, len(saves) // 3)]:
        _, other = shipped_world(domain, seed=99)
        other.world.restore(json.loads(json.dumps(saved)))
        assert other.world.snapshot() == saved
        resumed = Executive(
            target.task, other.skills, get_planner("fast-downward"), sense=other.sense,
            concurrent=other.concurrent,
        )  # fmt: skip
        resumed.resume_from(state)
        resumed.execute()
        done = len(state["report"]["executed"])
        assert other.world.goal_reached(), f"{domain}: restored after {done} steps"
        if not setup.concurrent:
            # Exact for one step at a time. With concurrent steps, a save holds what
            # the steps still running had done so far: they run again from there, as
            # they would on a robot, so the end may differ (docs/reliability.md).
            assert other.world.snapshot() == end, f"{domain}: restored after {done} steps"


def test_a_world_with_a_time_scale_waits_after_releasing_its_lock(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from plan_bridge.execution import clock
    from plan_bridge.planning.planner import PlanStep

    world = SimulatedWorld(rooms())
    waits: list[tuple[float, bool]] = []
    monkeypatch.setattr(clock.time, "sleep", lambda s: waits.append((s, world._lock.locked())))
    step = PlanStep("move", ("r1", "kitchen", "hall"))
    world.perform(step)
    assert waits == []  # no time scale: as fast as it goes
    assert world.sim_time == world.action_duration  # the world's clock moved on
    world.time_scale = 0.25
    assert world.clock.time_scale == 0.25
    world.perform(step)
    assert waits == [(0.25 * world.action_duration, False)]
    assert world.sim_time == 2 * world.action_duration
    saved = world.snapshot()
    world.perform(step)
    world.restore(saved)  # putting a state back takes no time, and sets the clock back
    assert len(waits) == 2
    assert world.sim_time == 2 * world.action_duration


def test_a_numeric_domain_runs_in_the_simulated_world_with_its_numbers() -> None:
    from plan_bridge.planning.planner import PlanStep

    corpus = Path(__file__).resolve().parents[1] / "pddl" / "corpus"
    task = load_task(
        corpus / "domain-numeric-without-requirement.pddl", corpus / "base" / "fuel-problem.pddl"
    )
    world = SimulatedWorld(task)
    assert world.values == {"(fuel van)": 5.0}
    ok, observations = world.perform(PlanStep("drive", ("van", "depot", "shop")))
    assert ok
    assert (("fuel", "van"), 4.0) in observations  # the number it changed, observed
    assert world.values["(fuel van)"] == 4.0
    world.values["(fuel van)"] = 0.0
    ok, _ = world.perform(PlanStep("drive", ("van", "shop", "depot")))
    assert not ok  # (>= (fuel van) 1) does not hold
    saved = world.snapshot()
    other = SimulatedWorld(task)
    other.restore(json.loads(json.dumps(saved)))
    assert other.values == {"(fuel van)": 0.0}
