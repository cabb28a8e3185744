"""fetch_drink (the main job): planned and scripted runs in the simulated home."""

from __future__ import annotations

import subprocess
import sys

import pytest
from pr2_missions import (
    DEFINED_OUTCOMES,
    DOMAINS,
    MemoPlanner,
    load_generator,
    run_planned,
    run_scripted,
    success_rate,
    summary,
    sweep_planned,
    target,
)

from plan_bridge.domain import load_task_from_text
from plan_bridge.executive import Executive
from plan_bridge.planning import get_planner

NAME = "fetch_drink"
SEEDS = range(20)


@pytest.fixture(scope="module")
def planner() -> MemoPlanner:
    return MemoPlanner(get_planner("fast-downward"))


@pytest.mark.timeout(60)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_reaches_the_goal_without_faults(problem: str, planner: MemoPlanner) -> None:
    run = run_planned(target(NAME, problem), seed=0, fail_rate=0.0, planner=planner)
    assert run.outcome == "succeeded"
    assert run.goal_reached
    assert run.faults == 0


@pytest.mark.timeout(120)
@pytest.mark.parametrize("fail_rate", [0.1, 0.2])
def test_planned_mission_recovers_from_faults_across_seeds(
    fail_rate: float, planner: MemoPlanner, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = sweep_planned(target(NAME), SEEDS, fail_rate, planner)
    with capsys.disabled():
        print(f"\n{summary(f'{NAME} p01 planned  fail {fail_rate}', runs)}")
    assert all(r.outcome in DEFINED_OUTCOMES for r in runs)
    # The executive's belief follows the world: it claims success exactly when it is true.
    assert all((r.outcome == "succeeded") == r.goal_reached for r in runs)
    assert sum(r.faults for r in runs) >= len(runs) // 2
    assert success_rate(runs) >= 0.9


@pytest.mark.timeout(60)
@pytest.mark.parametrize("fail_rate", [0.0, 0.1, 0.2])
def test_scripted_baseline_ends_in_a_defined_outcome(
    fail_rate: float, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = [run_scripted(target(NAME), seed, fail_rate) for seed in SEEDS]
    with capsys.disabled():
        print(f"\n{summary(f'{NAME} p01 scripted fail {fail_rate}', runs)}")
    assert all(r.outcome in DEFINED_OUTCOMES for r in runs)
    assert all((r.outcome == "succeeded") == r.goal_reached for r in runs)
    if fail_rate == 0.0:
        assert success_rate(runs) == 1.0


@pytest.mark.timeout(60)
def test_a_drink_on_another_shelf_is_picked_after_replanning(planner: MemoPlanner) -> None:
    mission = target(NAME)
    for seed in SEEDS:
        setup = mission.setup(seed=seed, fail_rate=0.1)
        if any(f.kind == "drink-misplaced" for f in setup.world.faults):
            break
    else:
        pytest.fail("no seed misplaces the drink")
    executive = Executive(mission.task, setup.skills, planner)
    assert executive.execute() == "succeeded"
    believed_shelf = next(f[2] for f in mission.task.initial_facts if f[0] == "on")
    picked = [s for s in executive.report.executed if s.startswith("(pick-drink")]
    assert len(picked) == 1 and believed_shelf not in picked[0]
    assert any(d["decision"] == "replan" for d in executive.report.decisions)


@pytest.mark.timeout(60)
def test_runs_are_reproducible_per_seed(planner: MemoPlanner) -> None:
    first = run_planned(target(NAME), 7, 0.2, planner)
    second = run_planned(target(NAME), 7, 0.2, planner)
    assert first.faults > 0
    assert (first.executed, first.fault_log) == (second.executed, second.fault_log)


@pytest.mark.timeout(60)
def test_generated_problem_loads_solves_and_runs(planner: MemoPlanner) -> None:
    script = DOMAINS / NAME / "generate.py"
    args = ["--rooms", "9", "--drinks", "3", "--seed", "4"]
    text = subprocess.run(
        [sys.executable, str(script), *args], capture_output=True, text=True, check=True
    ).stdout
    assert text == load_generator(NAME).problem_text(rooms=9, drinks=3, shelves=3, loops=4, seed=4)
    task = load_task_from_text((DOMAINS / NAME / "domain.pddl").read_text(), text)
    assert len(task.goal_facts) == 4
    mission = target(NAME)
    assert mission.module is not None
    setup = mission.module.setup(task, seed=0, fail_rate=0.0)
    executive = Executive(task, setup.skills, planner)
    assert executive.execute() == "succeeded"
    assert setup.world.goal_reached()
