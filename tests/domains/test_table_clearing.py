"""The table-clearing mission: planned and scripted, with and without faults."""

from __future__ import annotations

import importlib.util
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from plan_bridge.domain import load_task
from plan_bridge.events import StepFinished
from plan_bridge.executive import Executive
from plan_bridge.mission import Target, load_target
from plan_bridge.planning import UPPlanner, get_planner
from plan_bridge.semantics import ActionModel
from smach.testing import EventRecorder

DOMAIN = Path(__file__).resolve().parents[2] / "domains" / "table_clearing"
SEEDS = range(20)
RATES = (0.1, 0.2)
OUTCOMES = {"succeeded", "aborted", "preempted"}
SCRIPTED_OUTCOMES = {"done", "failed", "preempted"}


@dataclass(frozen=True)
class Run:
    """What one run ended with (everything that must be the same for the same seed)."""

    seed: int
    outcome: str | None
    goal_reached: bool
    faults: tuple[tuple[str, str, str], ...]
    facts: frozenset[tuple[str, ...]]
    decisions: tuple[str, ...]
    executed: tuple[str, ...] = ()


@pytest.fixture(scope="module")
def target() -> Target:
    return load_target(DOMAIN)


@pytest.fixture(scope="module")
def planner() -> UPPlanner:
    """The planner of ``plan-bridge run``."""
    return get_planner("fast-downward")


@pytest.fixture(scope="module")
def study_planner() -> UPPlanner:
    """The planner of the 20-seed studies here.

    pyperplan solves these small problems in ~0.05 s inside the warm worker, Fast
    Downward needs ~0.3 s (a subprocess per call): with 80 planned runs per file that
    decides whether the file takes 15 s or a minute. The success rates measured with
    Fast Downward are in the domain's README.
    """
    return get_planner("pyperplan")


def run_planned(target: Target, planner: UPPlanner, seed: int, fail_rate: float) -> Run:
    setup = target.setup(seed=seed, fail_rate=fail_rate)
    executive = Executive(target.task, setup.skills, planner, concurrent=setup.concurrent)
    outcome = executive.execute()
    world = setup.world
    assert executive.report.goal_reached == world.goal_reached()  # belief follows the world
    return Run(
        seed,
        outcome,
        world.goal_reached(),
        tuple(sorted((f.kind, f.action, f.detail) for f in world.faults)),
        world.facts,
        tuple(d["decision"] for d in executive.report.decisions),
        tuple(executive.report.executed),
    )


def run_scripted(target: Target, seed: int, fail_rate: float) -> Run:
    assert target.module is not None
    mission = target.module.scripted(target.task, seed=seed, fail_rate=fail_rate)
    outcome = mission.machine.execute()
    world = mission.world
    return Run(
        seed,
        outcome,
        world.goal_reached(),
        tuple(sorted((f.kind, f.action, f.detail) for f in world.faults)),
        world.facts,
        (),
    )


@pytest.fixture(scope="module")
def study(target: Target, study_planner: UPPlanner) -> dict[float, list[Run]]:
    """Planned runs over 20 seeds per fault rate (two at a time: the planner is a process)."""
    jobs = [(rate, seed) for rate in RATES for seed in SEEDS]
    with ThreadPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(lambda job: run_planned(target, study_planner, job[1], job[0]), jobs))
    return {
        rate: [r for (r_rate, _), r in zip(jobs, runs, strict=True) if r_rate == rate]
        for rate in RATES
    }


def _module(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"tc_{name}", DOMAIN / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# -- faults off ------------------------------------------------------------------------------
@pytest.mark.timeout(60)
@pytest.mark.parametrize(("problem", "objects"), [("p01", 2), ("p02", 5), ("p03", 10)])
def test_every_problem_reaches_the_goal_with_faults_off(
    problem: str, objects: int, planner: UPPlanner
) -> None:
    target = load_target(DOMAIN, problem)
    run = run_planned(target, planner, seed=0, fail_rate=0.0)
    assert run.outcome == "succeeded" and run.goal_reached
    assert run.faults == () and run.decisions == ()
    # The plan grows with the objects: a pick and a place each, then the cart run.
    assert len(run.executed) >= 2 * objects + 3


@pytest.mark.timeout(30)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_scripted_baseline_clears_every_problem_with_faults_off(problem: str) -> None:
    run = run_scripted(load_target(DOMAIN, problem), seed=0, fail_rate=0.0)
    assert run.outcome == "done" and run.goal_reached and run.faults == ()


# -- faults on -------------------------------------------------------------------------------
@pytest.mark.timeout(240)
@pytest.mark.parametrize("rate", RATES)
def test_planned_runs_reach_the_goal_despite_faults(
    study: dict[float, list[Run]], rate: float
) -> None:
    runs = study[rate]
    assert len(runs) == len(SEEDS)
    assert all(r.outcome in OUTCOMES for r in runs)
    assert all(r.goal_reached == (r.outcome == "succeeded") for r in runs)
    assert sum(len(r.faults) for r in runs) >= len(SEEDS) // 2  # the faults are real
    assert any(d in ("replan", "repair") for r in runs for d in r.decisions)
    # Measured: 20/20 at both rates (pyperplan here; Fast Downward too, see the
    # README); 18/20 leaves room for planner changes.
    assert sum(r.goal_reached for r in runs) >= 18


@pytest.mark.timeout(60)
def test_planned_runs_are_deterministic_per_seed(
    target: Target, study_planner: UPPlanner, study: dict[float, list[Run]]
) -> None:
    for seed in (2, 3):
        assert run_planned(target, study_planner, seed, 0.2) == study[0.2][seed]


@pytest.mark.timeout(60)
@pytest.mark.parametrize("rate", (0.0, *RATES))
def test_scripted_baseline_ends_in_a_defined_outcome(target: Target, rate: float) -> None:
    runs = [run_scripted(target, seed, rate) for seed in SEEDS]
    assert all(r.outcome in SCRIPTED_OUTCOMES for r in runs)
    assert all(r.goal_reached == (r.outcome == "done") for r in runs)
    reached = sum(r.goal_reached for r in runs)
    if rate == 0.0:
        assert reached == len(SEEDS)
    else:
        # Measured: 19/20 at 0.1, 12/20 at 0.2 (it fails on floor drops and blocked
        # corridors, which its author did not anticipate).
        assert 0 < reached < len(SEEDS)
    assert [run_scripted(target, 5, rate) for _ in range(2)] == [runs[5]] * 2


def test_planned_beats_scripted_where_the_script_did_not_anticipate_the_fault(
    target: Target, study: dict[float, list[Run]]
) -> None:
    rescued = [
        r.seed
        for r in study[0.2]
        if r.goal_reached and not run_scripted(target, r.seed, 0.2).goal_reached
    ]
    assert rescued


# -- skills ----------------------------------------------------------------------------------
def _world(target: Target) -> Any:
    assert target.module is not None
    return target.module.world.TableWorld(target.task, seed=0, fail_rate=0.0)


@pytest.mark.timeout(10)
def test_push_monitor_backs_up_a_jammed_cart_and_pushes_again(target: Target) -> None:
    world = _world(target)
    jams = iter([True])
    world._chance = lambda kind: kind == "wheels-stalled" and next(jams, False)
    skill = target.module.skills.push_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "cart": "cart1", "source": "table-n", "target": "doorway"}
    )
    recorder = EventRecorder()
    skill.add_listener(recorder)
    assert skill.execute() == "succeeded"
    entered = [e.path for e in recorder.of_kind("state_entered")]
    assert entered.count("/ROOT/BACK_UP") == 1 and entered.count("/ROOT/PUSH") == 2
    assert entered.count("/ROOT/PUSH/MONITOR_WHEELS") == entered.count("/ROOT/PUSH/DRIVE_CART") == 2
    assert skill.userdata.observations[("cart-at", "cart1", "doorway")] is True
    assert [f.kind for f in world.faults] == ["wheels-stalled"]


@pytest.mark.timeout(10)
def test_push_into_a_blocked_corridor_reports_it_not_clear(target: Target) -> None:
    world = _world(target)
    world._blocked.add(frozenset(("table-n", "doorway")))
    skill = target.module.skills.push_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "cart": "cart1", "source": "table-n", "target": "doorway"}
    )
    assert skill.execute() == "aborted"
    seen = skill.userdata.observations
    assert seen[("clear", "table-n", "doorway")] is False
    assert seen[("clear", "doorway", "table-n")] is False
    assert ("cart-at", "cart1", "table-n") in world.facts


@pytest.mark.timeout(10)
def test_pick_reports_an_object_that_fell_to_the_floor(target: Target) -> None:
    world = _world(target)
    world._chance = lambda kind: kind == "grasp-slip"
    world.rng.random = lambda: 0.0  # below FLOOR_SHARE: to the floor
    skill = target.module.skills.pick_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "item": "cup1", "spot": "zone-n"}
    )
    assert skill.execute() == "aborted"
    seen = skill.userdata.observations
    assert seen[("item-at", "cup1", "floor-n")] is True
    assert seen[("item-at", "cup1", "zone-n")] is False


@pytest.mark.timeout(60)
def test_a_misplaced_object_is_found_and_the_executive_replans(
    target: Target, study_planner: UPPlanner
) -> None:
    setup = target.setup(seed=0, fail_rate=0.0)
    world = setup.world
    # plate2 lies in zone-n, not in zone-s as the problem says.
    with world._lock:
        world._facts.discard(("item-at", "plate2", "zone-s"))
        world._facts.add(("item-at", "plate2", "zone-n"))
    executive = Executive(target.task, setup.skills, study_planner)
    recorder = EventRecorder()
    executive.add_listener(recorder)
    assert executive.execute() == "succeeded" and world.goal_reached()
    assert "replan" in [d["decision"] for d in executive.report.decisions]
    steps = [e.action for e in recorder.events if isinstance(e, StepFinished)]
    assert "(pick pr2 plate2 zone-n table-n)" in steps


# -- command line and generator --------------------------------------------------------------
@pytest.mark.timeout(60)
def test_generator_output_loads_and_solves(
    tmp_path: Path, planner: UPPlanner, capsys: pytest.CaptureFixture[str]
) -> None:
    generate = _module("generate")
    assert generate.main(["--objects", "14", "--seed", "5"]) == 0
    problem = tmp_path / "p14.pddl"
    problem.write_text(capsys.readouterr().out)
    task = load_task(DOMAIN / "domain.pddl", problem)
    assert len(task.objects_of_type("item")) == 14
    result = planner.solve(task, timeout=30)
    assert result.solved, result.explanation
    assert ActionModel(task).check_plan(result.actions, task.initial_facts).valid


def test_generator_is_reproducible_and_rejects_nonsense() -> None:
    generate = _module("generate")
    assert (
        generate.generate(5, 2, "clear-table-p02") == (DOMAIN / "problems" / "p02.pddl").read_text()
    )
    with pytest.raises(ValueError, match="--objects"):
        generate.generate(0, 1)
