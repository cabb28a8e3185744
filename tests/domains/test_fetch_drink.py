"""fetch_drink (the main job): a drink on another shelf, found and fetched after replanning.

What every mission does (faults, seeds, the scripted baseline, generated problems) is
tested in test_missions.py.
"""

from __future__ import annotations

import pytest
from pr2_missions import planner, setup_with_fault, target

from plan_bridge.execution.executive import Executive

NAME = "fetch_drink"


@pytest.mark.timeout(60)
def test_a_drink_on_another_shelf_is_picked_after_replanning() -> None:
    mission = target(NAME)
    setup = setup_with_fault(mission, "drink-misplaced")
    executive = Executive(mission.task, setup.skills, planner())
    assert executive.execute() == "succeeded"
    believed_shelf = next(f[2] for f in mission.task.initial_facts if f[0] == "on")
    picked = [s for s in executive.report.executed if s.startswith("(pick-drink")]
    assert len(picked) == 1 and believed_shelf not in picked[0]
    assert any(d["decision"] == "replan" for d in executive.report.decisions)
