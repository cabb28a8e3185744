"""fetch_drink (the main job): a drink on another shelf, found and fetched after replanning.

What every mission does (faults, seeds, the scripted baseline, generated problems) is
tested in test_missions.py.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from pr2_missions import planner, setup_with_fault, target

from plan_bridge.cli import main
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


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    ("problem", "orders", "expected"),
    [
        ("p01", "drinks.yaml", {"done": 3, "refused": 1}),
        ("p03", "drinks_p03.yaml", {"done": 4, "refused": 0}),
    ],
)
def test_drink_orders_stream_in_and_each_ends_done_or_refused_with_a_reason(
    problem: str,
    orders: str,
    expected: dict[str, int],
    capsys: pytest.CaptureFixture[str],
) -> None:
    folder = Path(__file__).resolve().parents[2] / "domains" / NAME
    args = ["run", str(folder), "--problem", problem, "--orders", str(folder / "orders" / orders)]
    assert main([*args, "--seed", "1", "--json"]) == 0
    out, err = capsys.readouterr()
    figures = json.loads(out)["orders"]
    assert {key: figures[key] for key in expected} == expected
    assert figures["failed"] == 0 and figures["orders"] == sum(expected.values())
    if expected["refused"]:
        assert "unknown object 'juice'" in err
