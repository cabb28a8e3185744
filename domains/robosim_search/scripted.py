"""robosim_search written by hand: find the object, then fetch it; no planner.

The baseline of the scripted-vs-planned study on this world. It drives the same robosim
skills as the planned mission (``skill_for``: navigate, open, pick, place) in the same
:class:`~plan_bridge.robosim.world.RobosimWorld`, and searches as a careful author would
without a model of where things are likely to be:

* go to where the world file put the object; if it is there, pick it;
* else sweep: the nearest place not looked at yet (by route from where the robot is),
  opening a closed location to look inside, until the object is seen; then pick it;
* carry it to the goal's spawn and put it down (``deliver``).

Each drive and action is tried three times. Goals: ``(At OBJECT SPAWN)`` with
``(HandEmpty ROBOT)`` if wanted, or ``(Holding ROBOT OBJECT)``::

    SEARCH (look where it was, then sweep nearest-first; pick) -> DELIVER -> succeeded
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import scripted_world
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.robosim.scripting import ATTEMPTS, SkillState, deliver, locked_halls, route
from plan_bridge.robosim.scripting import route_length as length
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["FindAndPick", "find_and_fetch", "scripted"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]


class FindAndPick(SkillState):
    """Look for ``item`` where it was put, then at every other place nearest-first;
    pick it where it is seen (``found``), or give up (``missing``)."""

    def __init__(self, world: RobosimWorld, robot: str, item: str) -> None:
        super().__init__(
            world,
            robot,
            outcomes=["found", "missing", "preempted"],
            output_keys=["searched", "found_at"],
        )
        self.item = item

    def execute(self, ud: smach.UserData) -> str:
        world, model = self.world, self.world.model
        places = [
            name
            for name, place in model.places.items()
            if place.spawns and place.fixture and not model.gates[place.fixture].is_charger
        ]
        first = model.item_place(self.item)
        looked: list[str] = []
        while True:
            left = [p for p in places if p not in looked]
            if not left:
                ud.searched = looked
                return "missing"
            here = self.here()
            if first in left:
                place = first
            else:
                place = min(left, key=lambda p: (length(world, route(world, here, p, ())), p))
            looked.append(place)
            if not self._try("navigate", here, place):
                continue
            fixture = model.places[place].fixture or ""
            closed = not world.sim.get_entity_by_name(fixture).is_open
            if closed and not self._try("open", fixture, place):
                continue
            if self._seen_here(place):
                ud.found_at = world.now()
                if self._try("pick", self.item, place, fixture):
                    ud.searched = looked
                    return "found"
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"

    def _try(self, action: str, *args: str) -> bool:
        for _ in range(ATTEMPTS):
            if self.skill(action, *args) == "succeeded":
                return True
            if action == "navigate":
                args = (self.here(), *args[1:])
        return False

    def _seen_here(self, place: str) -> bool:
        seen = dict(self.world.observe(self.world.robot(self.robot)))
        return bool(seen.get(("at", self.item.lower(), place.lower()), False))


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = scripted_world(FOLDER, task, seed=seed, fail_rate=fail_rate, variant=variant)
    return ScriptedMission(find_and_fetch(world, task.goal_facts), world)


def find_and_fetch(world: RobosimWorld, goal: Sequence[Fact]) -> smach.StateMachine:
    """The hand-written machine of a goal ``(At OBJECT SPAWN)`` [``(HandEmpty ROBOT)``]
    or ``(Holding ROBOT OBJECT)`` in ``world`` (any world with one robot)."""
    model = world.model
    robot = model.robots[0].name
    item = target = ""
    for fact in goal:
        if fact[0] == "at" and world.name(fact[1]) in model.items:
            item, target = world.name(fact[1]), world.name(fact[2])
        elif fact[0] == "holding":
            item = world.name(fact[2])
    if not item:
        raise ValueError(
            "the scripted baseline of robosim_search fetches one object: a goal (At OBJECT "
            f"SPAWN) [(HandEmpty ROBOT)] or (Holding ROBOT OBJECT); not {list(goal)}"
        )
    mission = smach.StateMachine(outcomes=OUTCOMES)
    mission.userdata.blocked = locked_halls(world)
    mission.userdata.legs = []
    mission.userdata.searched = []
    mission.userdata.found_at = None
    with mission:
        smach.StateMachine.add(
            "SEARCH",
            FindAndPick(world, robot, item),
            {"found": "DELIVER" if target else "succeeded", "missing": "aborted"},
        )
        if target:
            smach.StateMachine.add(
                "DELIVER",
                deliver(world, robot, item, target, holding=True),
                {"done": "succeeded"},
            )
    return mission
