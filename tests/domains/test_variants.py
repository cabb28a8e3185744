"""The 'unanticipated' world variants: faults the scripted baselines were not written for."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import load_target

DOMAINS = Path(__file__).resolve().parents[2] / "domains"


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    ("domain", "problem", "fault"),
    [("fetch_drink", "p01", "person-moved"), ("door_opening", "p02", "door-locked")],
)
def test_unanticipated_fault_defeats_the_script_but_not_the_planner(
    domain: str, problem: str, fault: str
) -> None:
    target = load_target(DOMAINS / domain, problem)
    mission = target.module.scripted(target.task, seed=0, fail_rate=0.0, variant="unanticipated")
    assert mission.machine.execute() == "aborted"
    assert not mission.world.goal_reached()
    assert any(f.kind == fault for f in mission.world.faults)

    setup = target.module.setup(target.task, seed=0, fail_rate=0.0, variant="unanticipated")
    executive = Executive(target.task, setup.skills)
    assert executive.execute() == "succeeded"
    assert setup.world.goal_reached()
    assert executive.report.replans >= 1


@pytest.mark.parametrize("domain", ["fetch_drink", "door_opening"])
def test_unknown_variants_are_refused(domain: str) -> None:
    target = load_target(DOMAINS / domain)
    with pytest.raises(ValueError, match="unknown variant 'sideways'"):
        target.module.setup(target.task, seed=0, fail_rate=0.0, variant="sideways")
