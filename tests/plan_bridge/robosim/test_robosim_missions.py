"""pyrobosim worlds as targets: prepare_mission, the CLI, seeded runs, events."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main
from plan_bridge.missions.mission import TargetError, load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.robosim.world import RobosimWorld

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"
CLOSE = FETCH / "events" / "close_hallway.yaml"


def run(target: str | Path, **options: object) -> dict:  # type: ignore[type-arg]
    goal = options.pop("goal", None)
    events = options.pop("events", None)
    loaded = load_target(target, goal=goal, events=events)  # type: ignore[arg-type]
    mission = prepare_mission(loaded, MissionOptions(**options))  # type: ignore[arg-type]
    mission.run()
    world = mission.world
    assert isinstance(world, RobosimWorld)
    executed = list(mission.executive.report.executed)
    return {**mission.figures(), "executed": executed, "crossed": dict(world.crossed)}


def test_a_seeded_run_with_faults_repeats_exactly() -> None:
    first = run(FETCH, seed=5, fail_rate=0.3)
    second = run(FETCH, seed=5, fail_rate=0.3)
    assert first["goal_reached"] and first["faults_injected"] > 0
    for key in ("executed", "outcome", "faults_injected", "sim_time_s", "distance_m"):
        assert first[key] == second[key]


def test_a_hallway_closed_on_the_way_leads_to_a_replan_through_the_office() -> None:
    figures = run(FETCH, fail_rate=0.0, events=CLOSE)
    assert figures["goal_reached"]
    assert figures["replans"] >= 1
    assert figures["world_changes"] == 2
    # To the kitchen through its hallway; back, once it closed, round through the office.
    assert figures["crossed"]["robot"] == [
        "hall_kitchen_living_room",
        "hall_kitchen_office",
        "hall_living_room_office",
    ]


def test_a_world_file_needs_a_goal_and_checks_it() -> None:
    with pytest.raises(TargetError, match="give the goal with --goal"):
        load_target(FETCH / "world.yaml")
    with pytest.raises(TargetError, match=r"no such goal .*did you mean fetch_soda"):
        load_target(FETCH, "fetch_sod")


def test_cli_problem_plan_check_and_run_on_a_world_file(
    test_world_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    goal = "(At apple0 table0_tabletop)"
    assert main(["problem", str(test_world_file), "--goal", goal]) == 0
    assert "(:goal (and (at apple0 table0_tabletop)))" in capsys.readouterr().out
    assert main(["plan", str(test_world_file), "--goal", goal]) == 0
    assert "(pick robot apple0 my_desk_desktop my_desk)" in capsys.readouterr().out
    assert main(["check", str(FETCH)]) == 0
    out = capsys.readouterr().out
    assert "fetch_soda: temporal" in out and "OK (3 problem(s) checked)" in out
    assert (
        main(["run", str(test_world_file), "--goal", goal, "--seed", "2", "--json", "--quiet"]) == 0
    )
    figures = json.loads(capsys.readouterr().out)
    assert figures["goal_reached"] and figures["sim_time_s"] > 0 and figures["distance_m"] > 0


def test_cli_bad_goal_is_bad_input_in_the_vocabulary_of_the_target(
    test_world_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", str(test_world_file), "--goal", "(At apple0 tabel0)"]) == 2
    assert "did you mean table0" in capsys.readouterr().err
    # A PDDL target's --goal is checked against its domain and problem
    # (tests/plan_bridge/cli/test_goal_option.py).
    assert main(["plan", "domains/fetch_drink", "--goal", "(At a b)"]) == 2
    assert "--goal:1:5: undeclared object or constant 'a'" in capsys.readouterr().err


def test_a_goal_the_world_blocks_is_refused_with_what_blocks_it(
    tmp_path: Path, test_world_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # (A goal blocked during the run - events - ends with exit 1 and the planner's
    # reason: test_shipped_worlds.py.)
    text = test_world_file.read_text().replace("$DATA", str(test_world_file.parent))
    locked = text.replace(
        "is_open: True\n    is_locked: False", "is_open: False\n    is_locked: True"
    )
    world = tmp_path / "locked.yaml"
    world.write_text(locked)
    code = main(["run", str(world), "--goal", "(At robot bedroom)", "--planner", "kairos"])
    err = capsys.readouterr().err
    assert code == 2
    assert "cannot get from kitchen to bedroom" in err and "closed and locked" in err


def test_a_goal_of_the_folder_is_named_by_goal_as_by_problem(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["problem", str(FETCH), "--goal", "open_fridge"]) == 0
    by_goal = capsys.readouterr().out
    assert main(["problem", str(FETCH), "--problem", "open_fridge"]) == 0
    assert capsys.readouterr().out == by_goal
    assert "(:goal (and (isopen fridge)))" in by_goal
    assert main(["problem", str(FETCH), "--goal", "open_frige"]) == 2
    err = capsys.readouterr().err
    assert "not a goal atom" in err and "did you mean open_fridge?" in err
