"""Generated buildings: the same arguments give the same world, and a run reaches its
goal on one with pyrobosim's default (auto) hallways and faults."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main as plan_bridge
from plan_bridge.robosim.buildings import Building, goals, main, world_data


def test_the_same_arguments_give_the_same_building() -> None:
    spec = Building(rooms=9, robots=2, deliveries=3, seed=4)
    assert world_data(spec) == world_data(Building(rooms=9, robots=2, deliveries=3, seed=4))
    data = world_data(spec)
    assert len(data["rooms"]) == 9 and len(data["hallways"]) == 12
    assert [r["name"] for r in data["robots"]] == ["robot0", "robot1"]
    assert "path_planner" not in data["robots"][0]  # plan_bridge's skills use none
    assert goals(spec)["deliver"].count("(At parcel") == 3


@pytest.mark.parametrize("bad", [{"rooms": 0}, {"robots": 5, "rooms": 4}, {"connection": "x"}])
def test_impossible_buildings_are_refused(bad: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        Building(**bad)  # type: ignore[arg-type]


@pytest.mark.timeout(300)
def test_a_building_with_auto_hallways_and_tables_in_the_middle_is_served_with_faults(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([str(tmp_path / "b"), "--rooms", "9", "--robots", "2", "--deliveries", "2"]) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "b")
    code = plan_bridge(["run", str(tmp_path / "b"), "--fail-rate", "0.2", "--json", "--quiet"])
    figures = json.loads(capsys.readouterr().out)
    assert code == 0 and figures["goal_reached"]
    assert figures["world_load_s"] > 0 and figures["task_s"] > 0
