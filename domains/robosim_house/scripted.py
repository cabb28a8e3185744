"""robosim_house written by hand: one SMACH machine with explicit recovery, no planner.

The baseline of the scripted-vs-planned study on this pyrobosim world. It drives the
same robosim skills as the planned missions, built from
:mod:`plan_bridge.robosim.scripting` (a door found closed is opened, a hallway found
locked is given up for another way, a failed drive or action is tried again, the robot
charges first when its battery would not last). Its author anticipated three kinds of
goal atoms, done in this order:

* ``(Has LOCATION OBJECT)`` / ``(At OBJECT SPAWN)``: carry the object there
  (``clear_table``), one object at a time, in the order of the goal;
* ``(Searched SPAWN)``: go there and look (``inspect_all``), the nearest first;
* ``(At ROBOT PLACE)``: end there (``through_doors``).

``(HandEmpty ROBOT)`` holds once every object is placed. Anything else is refused when
the machine is built; anything unanticipated while it runs (every way closed, three
failures in a row) ends it ``aborted``::

    DELIVER_1 (GO_TO_OBJECT -> OPEN -> PICK -> GO_TO_TARGET -> PLACE) -> DELIVER_2 ...
      -> SEARCH_1 (GO -> DETECT) ... -> END_AT (GO) -> succeeded
"""

from __future__ import annotations

from pathlib import Path

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import scripted_world
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.robosim.scripting import (
    KEYS,
    Act,
    charger_spot,
    deliver,
    go_to,
    locked_halls,
    route,
    route_length,
)
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["scripted"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]
_PART = ["done", "aborted", "preempted"]


class _Plan:
    """What the goal asks, in the baseline's terms (raises ValueError otherwise)."""

    def __init__(self, task: PlanningTask, world: RobosimWorld) -> None:
        model = world.model
        self.robot = model.robots[0].name
        self.deliveries: list[tuple[str, str]] = []
        self.searches: list[str] = []
        self.end_at: str | None = None
        for fact in task.goal_facts:
            name, args = fact[0], [world.name(a) for a in fact[1:]]
            if name == "has" and args[0] in model.gates and args[1] in model.items:
                places = model.spawn_places(args[0])
                if model.item_place(args[1]) not in places:
                    self.deliveries.append((args[1], places[0]))
            elif name == "at" and args[0] in model.items and args[1] in model.places:
                if model.item_place(args[0]) != args[1]:
                    self.deliveries.append((args[0], args[1]))
            elif name == "searched":
                self.searches.append(args[0])
            elif name == "at" and args[0] == self.robot and args[1] in model.places:
                self.end_at = args[1]
            elif name != "handempty":
                raise ValueError(
                    "the scripted baseline of robosim_house carries objects (Has LOCATION "
                    "OBJECT), looks at spawns (Searched SPAWN) and goes to a place (At ROBOT "
                    f"PLACE); not {' '.join(fact)}"
                )


def _nearest_first(world: RobosimWorld, start: str, spots: list[str]) -> list[str]:
    order, here, left = [], start, list(spots)
    while left:
        here = min(left, key=lambda s: route_length(world, route(world, here, s, ())))
        order.append(here)
        left.remove(here)
    return order


def _search(world: RobosimWorld, robot: str, spawn: str, charger: str | None) -> smach.StateMachine:
    location = world.model.places[spawn].fixture or ""
    sm = smach.StateMachine(outcomes=_PART, input_keys=KEYS, output_keys=KEYS)
    with sm:
        smach.StateMachine.add(
            "GO", go_to(world, robot, spawn, charger), {"arrived": "OPEN", "failed": "aborted"}
        )
        smach.StateMachine.add(
            "OPEN",
            Act(world, robot, "open", location, spawn),
            {"done": "DETECT", "failed": "aborted"},
        )
        smach.StateMachine.add(
            "DETECT", Act(world, robot, "detect", spawn, location), {"failed": "aborted"}
        )
    return sm


def _end_at(world: RobosimWorld, robot: str, place: str, charger: str | None) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=_PART, input_keys=KEYS, output_keys=KEYS)
    with sm:
        smach.StateMachine.add(
            "GO", go_to(world, robot, place, charger), {"arrived": "done", "failed": "aborted"}
        )
    return sm


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = scripted_world(FOLDER, task, seed=seed, fail_rate=fail_rate, variant=variant)
    model = world.model
    plan = _Plan(task, world)
    robot, charger = plan.robot, charger_spot(world)
    start = next(r.place for r in model.robots if r.name == robot)
    after_deliveries = plan.deliveries[-1][1] if plan.deliveries else start
    parts: list[tuple[str, smach.StateMachine]] = [
        (f"DELIVER_{item.upper()}", deliver(world, robot, item, target, charger))
        for item, target in plan.deliveries
    ]
    parts += [
        (f"SEARCH_{spawn.upper()}", _search(world, robot, spawn, charger))
        for spawn in _nearest_first(world, after_deliveries, plan.searches)
    ]
    if plan.end_at is not None:
        parts.append(("END_AT", _end_at(world, robot, plan.end_at, charger)))
    mission = smach.StateMachine(outcomes=OUTCOMES)
    mission.userdata.blocked = locked_halls(world)
    mission.userdata.legs = []
    with mission:
        for number, (label, part) in enumerate(parts):
            after = parts[number + 1][0] if number + 1 < len(parts) else "succeeded"
            smach.StateMachine.add(label, part, {"done": after})
    return ScriptedMission(mission, world)
