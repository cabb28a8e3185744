"""recharge: a battery monitor preempts long drives; the executive plans a recharge.

What every mission does (faults, seeds, the scripted baseline, generated problems) is
tested in test_missions.py.
"""

from __future__ import annotations

import pytest
from pr2_missions import BY_NAME, RATES, planner, setup_with_fault, sweep, target

from plan_bridge.belief import normalise_observations
from plan_bridge.execution.executive import Executive
from plan_bridge.planning.planner import PlanStep

NAME = "recharge"


@pytest.mark.timeout(60)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_without_faults_the_battery_lasts_the_whole_mission(problem: str) -> None:
    mission = target(NAME, problem)
    setup = mission.setup(seed=0, fail_rate=0.0)
    executive = Executive(mission.task, setup.skills, planner())
    assert executive.execute() == "succeeded"
    assert setup.world.recharges == 0 and not setup.world.battery_low()


@pytest.mark.timeout(240)
@pytest.mark.parametrize("rate", RATES)
def test_faults_make_the_executive_plan_recharges_across_seeds(rate: float) -> None:
    runs = sweep(NAME, rate)
    recharged = [r for r in runs if "(charge pr2)" in r.executed]
    assert len(recharged) >= len(runs) // 4
    assert all(r.goal_reached for r in recharged)
    # The run checked for reproducibility in test_missions.py recharges (the monitor fires).
    assert "(charge pr2)" in sweep(NAME, 0.2)[BY_NAME[NAME].seed].executed


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
def test_low_battery_leads_to_charging_and_the_deliveries_resume() -> None:
    mission = target(NAME, "p01")
    setup = setup_with_fault(mission, "battery-not-full")  # a partly charged battery
    executive = Executive(mission.task, setup.skills, planner())
    assert executive.execute() == "succeeded"
    executed = executive.report.executed
    charge = executed.index("(charge pr2)")
    assert executed[charge - 1].startswith("(plug-in pr2")
    assert any(step.startswith("(place") for step in executed[charge:])
    assert setup.world.recharges >= 1 and setup.world.goal_reached()
