"""recharge: a battery monitor preempts long drives; the executive plans a recharge."""

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
from plan_bridge.planning import PlanStep, get_planner
from plan_bridge.world import normalise_observations

NAME = "recharge"
SWEEP = "p02"
SEEDS = range(20)


@pytest.fixture(scope="module")
def planner() -> MemoPlanner:
    return MemoPlanner(get_planner("fast-downward"))


@pytest.mark.timeout(60)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_reaches_the_goal_without_faults_or_recharging(problem: str, planner: MemoPlanner) -> None:
    mission = target(NAME, problem)
    setup = mission.setup(seed=0, fail_rate=0.0)
    executive = Executive(mission.task, setup.skills, planner)
    assert executive.execute() == "succeeded"
    assert setup.world.goal_reached()
    assert setup.world.faults_injected == 0
    assert setup.world.recharges == 0 and not setup.world.battery_low()


@pytest.mark.timeout(120)
@pytest.mark.parametrize("fail_rate", [0.1, 0.2])
def test_planned_mission_recovers_from_faults_across_seeds(
    fail_rate: float, planner: MemoPlanner, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = sweep_planned(target(NAME, SWEEP), SEEDS, fail_rate, planner)
    with capsys.disabled():
        print(f"\n{summary(f'{NAME} {SWEEP} planned  fail {fail_rate}', runs)}")
    assert all(r.outcome in DEFINED_OUTCOMES for r in runs)
    assert all((r.outcome == "succeeded") == r.goal_reached for r in runs)
    recharged = [r for r in runs if "(charge pr2)" in r.executed]
    assert len(recharged) >= len(runs) // 4
    assert success_rate(runs) >= 0.9


@pytest.mark.timeout(60)
@pytest.mark.parametrize("fail_rate", [0.0, 0.1, 0.2])
def test_scripted_baseline_ends_in_a_defined_outcome(
    fail_rate: float, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = [run_scripted(target(NAME, SWEEP), seed, fail_rate) for seed in SEEDS]
    with capsys.disabled():
        print(f"\n{summary(f'{NAME} {SWEEP} scripted fail {fail_rate}', runs)}")
    assert all(r.outcome in DEFINED_OUTCOMES for r in runs)
    assert all((r.outcome == "succeeded") == r.goal_reached for r in runs)
    if fail_rate == 0.0:
        assert success_rate(runs) == 1.0


@pytest.mark.timeout(30)
def test_battery_monitor_preempts_a_drive_and_reports_low_battery() -> None:
    mission = target(NAME, "p01")
    setup = mission.setup(seed=0, fail_rate=0.0)
    world = setup.world
    world.battery = 30.5  # LOW is raised within the first metre
    skill, _ = setup.skills.create(PlanStep("move", ("pr2", "kitchen", "hallway")))
    assert skill.execute(None) == "aborted"
    seen = dict(normalise_observations(skill.userdata.observations))
    assert seen[("battery-low", "pr2")] and not seen[("battery-ok", "pr2")]
    # The drive was stopped and the robot went back to the nearer end of the corridor.
    assert seen[("at", "pr2", "kitchen")] and world.holds("at", "pr2", "kitchen")


@pytest.mark.timeout(60)
def test_low_battery_leads_to_charging_and_the_deliveries_resume(planner: MemoPlanner) -> None:
    mission = target(NAME, "p01")
    for seed in SEEDS:
        setup = mission.setup(seed=seed, fail_rate=0.1)
        if any(f.kind == "battery-not-full" for f in setup.world.faults):
            break
    else:
        pytest.fail("no seed starts with a partly charged battery")
    executive = Executive(mission.task, setup.skills, planner)
    assert executive.execute() == "succeeded"
    executed = executive.report.executed
    charge = executed.index("(charge pr2)")
    assert executed[charge - 1].startswith("(plug-in pr2")
    assert any(step.startswith("(place") for step in executed[charge:])
    assert setup.world.recharges >= 1 and setup.world.goal_reached()


@pytest.mark.timeout(60)
def test_runs_with_the_monitor_thread_are_reproducible_per_seed(planner: MemoPlanner) -> None:
    first = run_planned(target(NAME, SWEEP), 3, 0.2, planner)
    second = run_planned(target(NAME, SWEEP), 3, 0.2, planner)
    assert "(charge pr2)" in first.executed
    assert (first.executed, first.fault_log) == (second.executed, second.fault_log)
    assert first.sim_time == second.sim_time


@pytest.mark.timeout(60)
def test_generated_problem_loads_solves_and_runs(planner: MemoPlanner) -> None:
    script = DOMAINS / NAME / "generate.py"
    args = ["--rooms", "9", "--items", "3", "--seed", "2"]
    text = subprocess.run(
        [sys.executable, str(script), *args], capture_output=True, text=True, check=True
    ).stdout
    assert text == load_generator(NAME).problem_text(rooms=9, items=3, chords=3, seed=2)
    task = load_task_from_text((DOMAINS / NAME / "domain.pddl").read_text(), text)
    assert len(task.goal_facts) == 3
    mission = target(NAME)
    assert mission.module is not None
    setup = mission.module.setup(task, seed=0, fail_rate=0.0)
    assert Executive(task, setup.skills, planner).execute() == "succeeded"
    assert setup.world.goal_reached()
