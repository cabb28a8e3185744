"""The two-robot delivery: concurrent plan steps, recovery, determinism, baseline."""

from __future__ import annotations

import importlib.util
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import pytest

from plan_bridge.domain import load_task
from plan_bridge.events import StepFinished
from plan_bridge.executive import Executive
from plan_bridge.mission import Target, load_target
from plan_bridge.planning import UPPlanner, get_planner
from plan_bridge.semantics import ActionModel
from smach.testing import EventRecorder

DOMAIN = Path(__file__).resolve().parents[2] / "domains" / "two_robot_delivery"
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
    faults: tuple[tuple[float, str, str, str], ...]
    facts: frozenset[tuple[str, ...]]
    decisions: tuple[str, ...]
    executed: tuple[str, ...]
    sim_time: float


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


def execute(
    target: Target,
    planner: UPPlanner,
    seed: int,
    fail_rate: float,
    recorder: EventRecorder | None = None,
) -> tuple[Run, Executive]:
    setup = target.setup(seed=seed, fail_rate=fail_rate)
    assert setup.concurrent
    executive = Executive(target.task, setup.skills, planner, concurrent=True)
    if recorder is not None:
        executive.add_listener(recorder)
    outcome = executive.execute()
    world = setup.world
    assert executive.report.goal_reached == world.goal_reached()
    run = Run(
        seed,
        outcome,
        world.goal_reached(),
        # Thread order may interleave the log; each fault carries its robot's clock.
        tuple(sorted((f.time, f.kind, f.action, f.detail) for f in world.faults)),
        world.facts,
        tuple(d["decision"] for d in executive.report.decisions),
        tuple(sorted(executive.report.executed)),
        world.sim_time,
    )
    return run, executive


def run_scripted(target: Target, seed: int, fail_rate: float) -> Run:
    assert target.module is not None
    mission = target.module.scripted(target.task, seed=seed, fail_rate=fail_rate)
    outcome = mission.machine.execute()
    world = mission.world
    return Run(
        seed,
        outcome,
        world.goal_reached(),
        tuple(sorted((f.time, f.kind, f.action, f.detail) for f in world.faults)),
        world.facts,
        (),
        (),
        world.sim_time,
    )


@pytest.fixture(scope="module")
def study(target: Target, study_planner: UPPlanner) -> dict[float, list[Run]]:
    """Planned runs over 20 seeds per fault rate (two at a time: the planner is a process)."""
    jobs = [(rate, seed) for rate in RATES for seed in SEEDS]
    with ThreadPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(lambda job: execute(target, study_planner, job[1], job[0])[0], jobs))
    return {
        rate: [r for (r_rate, _), r in zip(jobs, runs, strict=True) if r_rate == rate]
        for rate in RATES
    }


def _parallel_robots(recorder: EventRecorder) -> list[set[str]]:
    """For each concurrent layer that ran, the robots whose steps ran in it."""
    layers: dict[str, set[str]] = {}
    for event in recorder.events:
        if isinstance(event, StepFinished) and "_PARALLEL_" in event.path:
            layer = event.path.rsplit("/", 1)[0]
            layers.setdefault(layer, set()).add(event.action.split()[1])
    return list(layers.values())


# -- faults off ------------------------------------------------------------------------------
@pytest.mark.timeout(60)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_every_problem_reaches_the_goal_with_both_robots_in_parallel(
    problem: str, planner: UPPlanner
) -> None:
    recorder = EventRecorder()
    run, _ = execute(load_target(DOMAIN, problem), planner, 0, 0.0, recorder)
    assert run.outcome == "succeeded" and run.goal_reached
    assert run.faults == () and run.decisions == ()
    assert {"r1", "r2"} in _parallel_robots(recorder)


@pytest.mark.timeout(30)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_scripted_baseline_delivers_every_problem_with_faults_off(problem: str) -> None:
    run = run_scripted(load_target(DOMAIN, problem), seed=0, fail_rate=0.0)
    assert run.outcome == "done" and run.goal_reached and run.faults == ()


# -- concurrency and recovery ----------------------------------------------------------------
@pytest.mark.timeout(60)
def test_steps_of_the_two_robots_run_inside_a_concurrence(
    target: Target, study_planner: UPPlanner
) -> None:
    recorder = EventRecorder()
    execute(target, study_planner, 0, 0.0, recorder)
    steps = [e for e in recorder.events if isinstance(e, StepFinished)]
    layers = _parallel_robots(recorder)
    assert layers and all(robots == {"r1", "r2"} for robots in layers)
    # Every step of the plan ran inside a PARALLEL layer but the ones where one robot
    # was already done.
    inside = [e for e in steps if "_PARALLEL_" in e.path]
    assert len(inside) >= len(steps) // 2
    assert all(e.path.split("/")[-1].startswith(f"{e.index:02d}_") for e in steps)


@pytest.mark.timeout(60)
def test_executive_recovers_from_a_fault_of_one_robot_while_the_other_goes_on(
    target: Target, study_planner: UPPlanner
) -> None:
    setup = target.setup(seed=0, fail_rate=0.0)
    world = setup.world
    world.blocked_door = frozenset(("office", "hall-west"))  # r1's way to its storeroom
    executive = Executive(target.task, setup.skills, study_planner, concurrent=True)
    recorder = EventRecorder()
    executive.add_listener(recorder)
    assert executive.execute() == "succeeded" and world.goal_reached()
    assert [(f.kind, f.action) for f in world.faults] == [
        ("door-blocked", "(move r1 office hall-west)")
    ]
    decisions = [d["decision"] for d in executive.report.decisions]
    assert {"repair", "replan"} & set(decisions)
    failed = [e for e in recorder.events if isinstance(e, StepFinished) and e.outcome == "aborted"]
    assert [e.action for e in failed] == ["(move r1 office hall-west)"]
    assert "_PARALLEL_" in failed[0].path
    # After the recovery r1 goes round through the lab, still side by side with r2.
    assert "(move r1 office lab)" in executive.report.executed
    assert {"r1", "r2"} in _parallel_robots(recorder)[1:]


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
    assert any(d in ("replan", "repair", "retry") for r in runs for d in r.decisions)
    # Measured: 20/20 at both rates (pyperplan here; Fast Downward too, see the
    # README); 18/20 leaves room for planner changes.
    assert sum(r.goal_reached for r in runs) >= 18


@pytest.mark.timeout(60)
def test_concurrent_runs_are_deterministic_per_seed(
    target: Target, study_planner: UPPlanner, study: dict[float, list[Run]]
) -> None:
    for seed in (1, 4):
        assert execute(target, study_planner, seed, 0.2)[0] == study[0.2][seed]


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
        # Measured: 15/20 at 0.1, 12/20 at 0.2 (blocked doors and items falling off
        # on the way are not anticipated by its author).
        assert 0 < reached < len(SEEDS)
    # Two robots in a Concurrence, yet the same seed gives the same run.
    assert [run_scripted(target, 3, rate) for _ in range(2)] == [runs[3]] * 2


# -- command line and generator --------------------------------------------------------------
def _generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("trd_generate", DOMAIN / "generate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.timeout(60)
def test_generator_output_loads_and_solves(
    tmp_path: Path, planner: UPPlanner, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _generator().main(["--items", "5", "--seed", "9"]) == 0
    problem = tmp_path / "p05.pddl"
    problem.write_text(capsys.readouterr().out)
    task = load_task(DOMAIN / "domain.pddl", problem)
    assert len(task.objects_of_type("item")) == 10
    result = planner.solve(task, timeout=30)
    assert result.solved, result.explanation
    assert ActionModel(task).check_plan(result.actions, task.initial_facts).valid


def test_generator_is_reproducible() -> None:
    text = _generator().generate(2, 2, "deliver-p02")
    assert text == (DOMAIN / "problems" / "p02.pddl").read_text()
