"""Looking for things (issue 36): an object moved while the robot drives to it is
searched for and fetched; one taken away ends the run naming it and the places
searched; a new object seen joins the belief; events remove, add, and a seeded place."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.belief.whereabouts import ABSENT, places_of
from plan_bridge.missions.mission import load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.robosim.events import EventError, check_events, parse_events
from plan_bridge.robosim.world import RobosimWorld

SEARCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_search"


def run(events: str, **options: Any) -> Any:
    goal = options.pop("goal", None)
    target = load_target(SEARCH, goal=goal, events=SEARCH / "events" / f"{events}.yaml")
    mission = prepare_mission(target, MissionOptions(**options))
    mission.run()
    assert isinstance(mission.world, RobosimWorld)
    mission.world.close()
    return mission


def test_a_moved_object_is_searched_for_and_fetched() -> None:
    mission = run("moved", seed=3, fail_rate=0.0)
    report = mission.executive.report
    assert report.goal_reached
    assert any(step.startswith("(search robot soda") for step in report.executed)


def test_an_object_taken_away_ends_naming_it_and_every_place_searched() -> None:
    mission = run("taken", seed=2, fail_rate=0.0)
    report = mission.executive.report
    assert report.outcome == "aborted"
    assert report.explanation.startswith("soda not found")
    for place in ("counter_left", "fridge_inside", "nightstand_desktop", "shelf_board"):
        assert place in report.explanation
    assert {f[2] for f in mission.executive.belief.facts if f[0] == ABSENT} >= {
        "counter_left",
        "office_desk_desktop",
    }


def test_an_object_never_heard_of_seen_on_the_way_joins_the_belief() -> None:
    # A cup is put on the office desk; the robot is sent there and sees it.
    mission = run("new_cup", seed=0, fail_rate=0.0, goal="(At robot office_desk_desktop)")
    assert ("at", "cup0", "office_desk_desktop") in mission.executive.belief.facts
    view = mission.executive.task_view
    assert view is not None and view.objects()["cup0"] == "item"


def test_events_take_objects_away_add_new_ones_and_draw_a_place() -> None:
    events = parse_events(
        [
            {"at": 1, "remove": "soda"},
            {"at": 2, "add": "cup0", "category": "water", "to": "table_top"},
            {"at": 3, "move": "cup0", "to": ["shelf_top", "table_top"]},
        ]
    )
    check_events(events, ["table"], ["soda"], ["table_top", "shelf_top"])
    places = {events[2].drawn(seed).to for seed in range(20)}
    assert places == {"shelf_top", "table_top"}
    assert events[2].drawn(7) == events[2].drawn(7)


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ({"at": 1, "add": "cup0", "to": "table_top"}, "needs category"),
        ({"at": 1, "remove": "cup9"}, "no object 'cup9'"),
        ({"at": 1, "add": "soda", "category": "coke", "to": "table_top"}, "already a name"),
        ({"at": 1, "move": "soda", "to": ["table_top", "roof"]}, "no object spawn"),
    ],
)
def test_bad_events_are_refused_with_the_reason(item: dict[str, Any], message: str) -> None:
    with pytest.raises(EventError, match=message):
        check_events(parse_events([item]), ["table"], ["soda"], ["table_top"])


def watched(world: str, events: str, seed: int) -> tuple[Any, dict[str, set[str]], list[float]]:
    """A run of find_and_fetch on ``world`` (a file of robosim_search): the mission,
    where each robot looked for the soda and did not find it, when it was found."""
    goal = "(and (At soda foyer_table_tabletop) (HandEmpty robot))"
    target = load_target(SEARCH / world, goal=goal, events=SEARCH / "events" / f"{events}.yaml")
    mission = prepare_mission(target, MissionOptions(seed=seed, fail_rate=0.0))
    belief, sim = mission.executive.belief, mission.world
    assert isinstance(sim, RobosimWorld)
    looked: dict[str, set[str]] = {}
    found: list[float] = []

    def watch() -> None:
        facts = belief.facts
        at, held = places_of(facts)
        for fact in facts:
            if fact[0] == ABSENT and fact[1] == "soda":
                for robot in ("robot", "robot2"):
                    if fact[2] in at.get(robot, ()):
                        looked.setdefault(robot, set()).add(fact[2])
        if looked and not found and ("soda" in at or "soda" in held):
            found.append(sim.now())

    belief.add_listener(watch)
    mission.run()
    sim.close()
    return mission, looked, found


def test_two_robots_look_at_different_places_and_find_it_sooner_than_one() -> None:
    # Seed 9 moves the soda to the living room's shelf: the robot alone looks in the
    # kitchen and the office first; with two, the second looks in the living room.
    one, _, one_found = watched("world.yaml", "moved", 9)
    two, looked, two_found = watched("world_two_robots.yaml", "moved", 9)
    assert one.executive.report.goal_reached and two.executive.report.goal_reached
    assert set(looked) == {"robot", "robot2"}
    assert not looked["robot"] & looked["robot2"]
    assert two_found[0] < one_found[0]
    searches = [d["reason"] for d in two.executive.report.decisions if d["decision"] == "search"]
    assert any(reason.startswith("soda found at shelf_board") for reason in searches)
    # A place ruled out while the other robot drives: they look further at once.
    assert any(reason.endswith("the robots look further") for reason in searches)


def test_an_object_never_heard_of_seen_on_the_way_joins_the_knowledge_base() -> None:
    target = load_target(
        SEARCH,
        goal="(At robot office_desk_desktop)",
        events=SEARCH / "events" / "new_cup.yaml",
    )
    mission = prepare_mission(target, MissionOptions(seed=0, fail_rate=0.0))
    knowledge = mission.attach_knowledge()
    assert "cup0" not in knowledge.objects
    assert mission.run() == "succeeded"
    assert knowledge.objects["cup0"] == "item"
    # Seeing it was no reason to replan; a goal may name it now.
    assert not any("cup0" in d["reason"] for d in mission.executive.report.decisions)
    knowledge.set_goal("(Holding robot cup0)")
    assert mission.run() == "succeeded"
    assert mission.executive.report.executed[-1].startswith("(pick robot cup0")
    assert isinstance(mission.world, RobosimWorld)
    mission.world.close()
