"""RobosimWorld and its skills: statuses, observations, preempt, faults, events."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.planning.planner import PlanStep
from plan_bridge.robosim.events import EventError, WorldEvent, load_events
from plan_bridge.robosim.results import ActionResult
from plan_bridge.robosim.skills import skill_for
from plan_bridge.robosim.world import RobosimWorld

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"


def run_skill(world: RobosimWorld, action: str, *args: str) -> tuple[str, dict]:  # type: ignore[type-arg]
    sm = skill_for(world, action, *args)
    outcome = sm.execute()
    return outcome, dict(sm.userdata["observations"])


@pytest.mark.parametrize(
    ("status", "outcome"),
    [
        ("SUCCESS", "succeeded"),
        ("CANCELED", "preempted"),
        ("PRECONDITION_FAILURE", "aborted"),
        ("PLANNING_FAILURE", "aborted"),
        ("EXECUTION_FAILURE", "aborted"),
        ("POSTCONDITION_FAILURE", "aborted"),
        ("INVALID_ACTION", "aborted"),
    ],
)
def test_execution_status_maps_to_skill_outcomes(status: str, outcome: str) -> None:
    assert ActionResult(status).outcome == outcome


def test_skills_act_on_the_robot_and_report_what_it_sees(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    outcome, seen = run_skill(world, "navigate", "robot", "kitchen", "table0_tabletop")
    assert outcome == "succeeded"
    assert seen[("at", "robot", "table0_tabletop")] is True
    assert seen[("at", "robot", "kitchen")] is False
    assert seen[("at", "gala", "table0_tabletop")] is True  # what is on the table
    assert seen[("at", "apple0", "table0_tabletop")] is False
    assert seen[("islocked", "table0")] is True
    assert world.now() > 0
    outcome, seen = run_skill(world, "pick", "robot", "gala", "table0_tabletop", "table0")
    assert outcome == "succeeded"
    assert seen[("holding", "robot", "gala")] is True
    assert seen[("handempty", "robot")] is False
    # Opening needs an empty hand: pyrobosim's PRECONDITION_FAILURE -> aborted.
    outcome, seen = run_skill(world, "open", "robot", "table0", "table0_tabletop")
    assert outcome == "aborted"
    outcome, _ = run_skill(world, "place", "robot", "gala", "table0_tabletop", "table0")
    assert outcome == "succeeded"
    assert world.truth(("at", "gala", "table0_tabletop"))
    # The trash is closed; the robot is not there: picking fuji fails before acting.
    outcome, seen = run_skill(world, "pick", "robot", "fuji", "trash_top", "trash")
    assert outcome == "aborted"
    assert seen[("at", "robot", "trash_top")] is False
    outcome, seen = run_skill(world, "navigate", "robot", "table0_tabletop", "trash_top")
    outcome, seen = run_skill(world, "open", "robot", "trash", "trash_top")
    assert (outcome, seen[("isopen", "trash")]) == ("succeeded", True)
    outcome, seen = run_skill(world, "detect", "robot", "trash_top", "trash")
    assert outcome == "succeeded" and seen[("at", "fuji", "trash_top")] is True
    assert world.truth(("searched", "trash_top"))
    assert world.figures()["actions_run"] == 8


def test_a_closed_hallway_refuses_the_crossing(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    world.sim.close_location("hall_bedroom_kitchen")
    run_skill(world, "navigate", "robot", "kitchen", "hall_bedroom_kitchen_door_kitchen")
    outcome, seen = run_skill(
        world,
        "cross",
        "robot",
        "hall_bedroom_kitchen_door_kitchen",
        "hall_bedroom_kitchen_door_bedroom",
        "hall_bedroom_kitchen",
    )
    assert outcome == "aborted"
    assert seen[("isopen", "hall_bedroom_kitchen")] is False
    assert seen[("at", "robot", "hall_bedroom_kitchen_door_kitchen")] is True


def test_a_preempt_cancels_the_robots_drive(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    world.time_scale = 1.0  # real time: the drive lasts seconds
    robot = world.robot("robot")
    sm = skill_for(world, "navigate", "robot", "kitchen", "hall_bathroom_kitchen_door_kitchen")
    result: list[str] = []
    runner = threading.Thread(target=lambda: result.append(sm.execute()))
    runner.start()
    moving = threading.Event()
    for _ in range(400):  # until the robot is on its way
        if robot.executing_nav:
            moving.set()
            break
        runner.join(0.01)
    assert moving.is_set()
    sm.request_preempt()
    runner.join(timeout=30)
    assert not runner.is_alive()
    assert result == ["preempted"]
    assert world.spot_of(robot) != "hall_bathroom_kitchen_door_kitchen"
    assert not robot.is_busy()


def test_events_file_errors_name_the_item_and_what_is_allowed(tmp_path: Path) -> None:
    events = tmp_path / "events.yaml"
    events.write_text("- at: 3\n  close: hall_a\n- at: -1\n  open: hall_b\n")
    with pytest.raises(EventError, match=r"events.yaml:3: at: must be seconds >= 0 or a window"):
        load_events(events)
    events.write_text("- at: 3\n  shut: hall_a\n")
    with pytest.raises(EventError, match=r"events.yaml:1: unknown key 'shut'.*open: NAME"):
        load_events(events)
    events.write_text("- at: 3\n  move: soda\n")
    with pytest.raises(EventError, match="needs to: SPAWN"):
        load_events(events)
    assert load_events(FETCH / "events" / "close_hallway.yaml")[0] == WorldEvent(
        22.0,
        "close",
        "hall_kitchen_living_room",
        None,
        str(FETCH / "events" / "close_hallway.yaml") + ":3",
    )


def test_an_event_window_is_drawn_from_the_seed_the_same_for_its_items(
    test_world_file: Path, tmp_path: Path
) -> None:
    events = tmp_path / "events.yaml"
    events.write_text(
        "- at: [5, 20]\n  close: hall_bedroom_kitchen\n"
        "- at: [5, 20]\n  lock: hall_bedroom_kitchen\n- at: 2\n  open: hall_bedroom_kitchen\n"
    )
    loaded = load_events(events)
    assert [e.window for e in loaded] == [None, (5.0, 20.0), (5.0, 20.0)]
    times = {}
    for seed in (1, 2, 3):
        world = RobosimWorld(test_world_file, seed=seed, events=loaded)
        again = RobosimWorld(test_world_file, seed=seed, events=loaded)
        assert world.next_event_time() == again.next_event_time() == 2.0
        for each in (world, again):
            each.elapse(2.0)
            each.apply_due_events()
        times[seed] = world.next_event_time()
        assert times[seed] == again.next_event_time()
        assert times[seed] is not None and 5.0 <= times[seed] <= 20.0
        world.elapse(20.0)
        assert len(world.apply_due_events()) == 2  # closed and locked at that moment
    assert len(set(times.values())) == 3  # other seeds, other moments
    events.write_text("- at: [20, 5]\n  close: hall_bedroom_kitchen\n")
    with pytest.raises(
        EventError, match=r"events.yaml:1: at: \[20, 5\]: the window's start is after"
    ):
        load_events(events)
    events.write_text("- at: [1, 2, 3]\n  close: hall_bedroom_kitchen\n")
    with pytest.raises(EventError, match=r"or a window \[LO, HI\]"):
        load_events(events)


def test_events_with_unknown_names_are_refused(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    with pytest.raises(EventError, match="did you mean hall_bedroom_kitchen"):
        world.schedule([WorldEvent(1.0, "close", "hall_bedroom_kitchn")])


def test_an_event_due_during_a_drive_happens_during_it(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    # An object is moved while the robot drives (0.75 s): it happens at 0.3 s.
    world.schedule([WorldEvent(0.3, "move", "banana0", "counter0_left")])
    outcome, _ = run_skill(
        world, "navigate", "robot", "kitchen", "hall_bedroom_kitchen_door_kitchen"
    )
    assert outcome == "succeeded"
    assert world.changes and "banana0 moved to counter0_left" in world.changes[0]
    assert world.truth(("at", "banana0", "counter0_left"))


def test_robots_acting_at_once_on_timelines_of_their_own_overlap_in_time(
    test_world_file: Path,
) -> None:
    """A world node runs robot nodes' calls in threads of their own: their durations
    overlap on the world's clock instead of adding up."""
    world = RobosimWorld(test_world_file, seed=0)
    started = threading.Barrier(2)

    def act(seconds: float) -> None:
        with world.own_timeline():
            started.wait(5)
            world.elapse(seconds)

    threads = [threading.Thread(target=act, args=(s,)) for s in (10.0, 8.0)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(10)
    assert world.now() == pytest.approx(10.0)
    with world.own_timeline():  # one thread alone: its actions follow one another
        world.elapse(2.0)
        world.elapse(3.0)
    assert world.now() == pytest.approx(15.0)
    world.elapse(1.0)  # outside a timeline: the clock moves on by the duration
    assert world.now() == pytest.approx(16.0)
    world.close()


def test_adopt_makes_the_world_agree_with_a_users_skill(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file)
    world.adopt(PlanStep("navigate", ("robot", "kitchen", "table0_tabletop")), [])
    assert world.spot_of(world.robot("robot")) == "table0_tabletop"
    world.adopt(PlanStep("pick", ("robot", "gala", "table0_tabletop", "table0")), [])
    assert world.truth(("holding", "robot", "gala"))
    world.adopt(PlanStep("open", ("robot", "trash", "trash_top")), [(("islocked", "trash"), True)])
    assert world.truth(("isopen", "trash")) and world.truth(("islocked", "trash"))


def test_snapshot_and_restore_put_the_world_back(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file, seed=4, fail_rate=0.5)
    run_skill(world, "navigate", "robot", "kitchen", "table0_tabletop")
    saved = world.snapshot()
    run_skill(world, "pick", "robot", "gala", "table0_tabletop", "table0")
    run_skill(world, "navigate", "robot", "table0_tabletop", "trash_top")
    other = RobosimWorld(test_world_file, seed=4, fail_rate=0.5)
    other.restore(saved)
    assert other.snapshot() == saved
    assert other.spot_of(other.robot("robot")) == "table0_tabletop"
    assert other.now() == pytest.approx(saved["time"])
