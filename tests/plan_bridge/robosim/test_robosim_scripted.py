"""The scripted baseline of domains/robosim_fetch: one hand-written SMACH machine over
the robosim skills, with its own recoveries (retry, another hallway, charge first)."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

import smach
from plan_bridge.missions.mission import ScriptedMission, TargetError, load_target
from plan_bridge.robosim.world import RobosimWorld

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"


def baseline(problem: str | None = None, **options: Any) -> ScriptedMission:
    target = load_target(FETCH, problem)
    assert target.module is not None, "the world folder's Python is loaded"
    mission: ScriptedMission = target.module.scripted(target.task, **options)
    return mission


def run(mission: ScriptedMission) -> tuple[str, smach.UserData]:
    """Execute the baseline's machine: its outcome and its userdata (legs, blocked)."""
    machine = mission.machine
    assert isinstance(machine, smach.StateMachine)
    return str(machine.execute()), machine.userdata


def test_the_scripted_baseline_charges_first_and_reaches_the_goal_without_faults() -> None:
    mission = baseline(seed=0, fail_rate=0.0)
    world = mission.world
    assert isinstance(world, RobosimWorld)
    outcome, ud = run(mission)
    assert outcome == "succeeded"
    assert world.goal_reached() and world.faults == 0
    legs = ud.legs
    # 25 % at the start is too little for the trip: the charger comes first.
    assert legs[0] == "navigate living_room charger_dock"
    assert world.figures()["battery_used"] > 0 and world.charged["robot"] > 0
    assert ud.blocked == []


def test_the_scripted_baseline_goes_through_the_office_when_a_hallway_closes() -> None:
    mission = baseline(seed=0, fail_rate=0.0, variant="close_hallway_early")
    world = mission.world
    assert isinstance(world, RobosimWorld)
    outcome, ud = run(mission)
    assert outcome == "succeeded"
    assert world.goal_reached() and len(world.changes) == 2
    assert ud.blocked == ["hall_kitchen_living_room"]
    crossed = [leg.split()[-1] for leg in ud.legs if leg.startswith("cross")]
    # Seen locked from its door, never tried: only the office's hallways are crossed.
    assert set(crossed) == {"hall_living_room_office", "hall_kitchen_office"}
    assert "navigate charger_dock hall_kitchen_living_room_door_living_room" in ud.legs


def test_the_scripted_baseline_retries_a_failed_drive_and_repeats_with_its_seed() -> None:
    ends = []
    for _ in range(2):
        mission = baseline(seed=5, fail_rate=0.3, variant="close_hallway")
        outcome, ud = run(mission)
        assert outcome == "succeeded"
        legs = ud.legs
        assert any(a == b for a, b in itertools.pairwise(legs)), legs  # a retried leg
        ends.append((legs, mission.world.figures()))
    assert ends[0] == ends[1] and ends[0][1]["faults_injected"] > 0


def test_the_scripted_baseline_refuses_a_goal_it_was_not_written_for() -> None:
    with pytest.raises(ValueError, match=r"fetches one object to a spawn"):
        baseline("open_fridge", seed=0, fail_rate=0.0)


def test_a_world_variant_is_an_events_file_of_the_folder() -> None:
    target = load_target(FETCH)
    with pytest.raises(TargetError, match=r"no world variant 'close_halway'.*close_hallway"):
        target.setup(seed=0, fail_rate=0.0, variant="close_halway")
    world = target.setup(seed=0, fail_rate=0.0, variant="close_hallway_early").world
    assert isinstance(world, RobosimWorld) and world.next_event_time() == 5.0
    world.close()
