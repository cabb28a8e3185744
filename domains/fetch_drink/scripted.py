"""fetch_drink written by hand: one SMACH machine with explicit recovery, no planner.

This is how the mission would be scripted without a planner (the baseline of the
scripted-vs-planned study). The author read the problem once, wrote down the
orders, computed the routes on the map as it was believed to be, and hard-coded the
recoveries they anticipated:

* a person in a corridor: wait and try again (inside the DRIVE skill, as planned);
* a blocked corridor: drive back to where the leg began and take ONE precomputed
  detour that shares no corridor with the first route; if that is blocked too, fail;
* fridge handle slips or the seal holds: the open skill's own three attempts;
* the drink is not on the believed shelf: SCAN every shelf of the fridge;
* the grasp slips: the pick skill's three attempts; after that, fail.

Unanticipated trouble (a second blocked route, three slips in a row, a fridge that
will not open) ends the mission ``aborted``; a planner-based executive would retry
or replan. Per order the machine is::

    GO_TO_FRIDGE_i -> OPEN_FRIDGE_i -> FIND_DRINK_i -> PICK_i -> CLOSE_FRIDGE_i
      -> GO_TO_PERSON_i -> HAND_OVER_i -> (next order | succeeded)
    GO_TO_X = FOLLOW_ROUTE --blocked--> RETURN_TO_START -> FOLLOW_DETOUR
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import PlanningTask

from .skills import (
    DRIVE_ATTEMPTS,
    close_fridge_machine,
    drive_machine,
    grasp_machine,
    hand_over_machine,
    open_fridge_machine,
)
from .world import CONGESTION_WAIT, FetchDrinkWorld

__all__ = ["follow_route", "scripted"]

OUTCOMES = ["succeeded", "aborted", "preempted"]


def follow_route(world: FetchDrinkWorld, route: Sequence[str] | None) -> smach.Iterator:
    """Drive a fixed route corridor by corridor, each with the DRIVE skill's retries.

    ::

        Iterator over corridors [ NEXT_CORRIDOR -> DRIVE = Retry x3 [...] -> MARK_REACHED ]

    ``reached`` lists the places actually reached, so a recovery can drive back.
    """
    places = list(route or [])
    legs = list(itertools.pairwise(places))
    follow = smach.Iterator(
        outcomes=["arrived", "blocked", "preempted"],
        input_keys=["robot"],
        output_keys=["reached"],
        it=legs,
        it_label="corridor",
        exhausted_outcome="arrived" if places else "blocked",
    )
    follow.userdata.reached = places[:1]
    leg = smach.StateMachine(
        outcomes=["next", "blocked", "preempted"],
        input_keys=["robot", "corridor", "reached"],
        output_keys=["reached"],
    )

    @smach.cb_interface(
        outcomes=["ready"], input_keys=["corridor"], output_keys=["origin", "destination"]
    )
    def next_corridor(ud: smach.UserData) -> str:
        ud.origin, ud.destination = ud.corridor
        return "ready"

    @smach.cb_interface(outcomes=["next"], input_keys=["destination"], io_keys=["reached"])
    def mark_reached(ud: smach.UserData) -> str:
        ud.reached = [*ud.reached, ud.destination]
        return "next"

    with leg:
        smach.StateMachine.add("NEXT_CORRIDOR", smach.CBState(next_corridor), {"ready": "DRIVE"})
        smach.StateMachine.add(
            "DRIVE",
            drive_machine(world),
            {"arrived": "MARK_REACHED", "congested": "blocked"},
        )
        smach.StateMachine.add("MARK_REACHED", smach.CBState(mark_reached))
    with follow:
        smach.Iterator.set_contained_state("LEG", leg, loop_outcomes=["next"])
    return follow


class ReturnToStart(smach.State):
    """Drive back along the corridors just driven (they were passable a minute ago)."""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["returned", "blocked"], input_keys=["robot", "reached"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        back = list(reversed(ud.reached))
        for origin, destination in itertools.pairwise(back):
            for _ in range(DRIVE_ATTEMPTS):
                outcome = self.world.drive(ud.robot, origin, destination)
                if outcome != "congested":
                    break
                self.world.wait(CONGESTION_WAIT)
            if outcome != "arrived":
                return "blocked"
        return "returned"


def go_to(world: FetchDrinkWorld, start: str, goal: str) -> smach.StateMachine:
    """FOLLOW_ROUTE --blocked--> RETURN_TO_START -> FOLLOW_DETOUR (both routes fixed now)."""
    route = world.route(start, goal)
    used = {frozenset(c) for c in zip(route or [], (route or [])[1:], strict=False)}
    detour = world.route(start, goal, avoid=used)
    sm = smach.StateMachine(outcomes=["arrived", "failed", "preempted"], input_keys=["robot"])
    with sm:
        smach.StateMachine.add(
            "FOLLOW_ROUTE", follow_route(world, route), {"blocked": "RETURN_TO_START"}
        )
        smach.StateMachine.add(
            "RETURN_TO_START",
            ReturnToStart(world),
            {"returned": "FOLLOW_DETOUR", "blocked": "failed"},
        )
        smach.StateMachine.add("FOLLOW_DETOUR", follow_route(world, detour), {"blocked": "failed"})
    return sm


class ScanShelves(smach.State):
    """Find the drink: the camera sees every shelf of the open fridge at once."""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(
            outcomes=["found", "missing"], input_keys=["drink", "fridge"], output_keys=["shelf"]
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        shelf = self.world.look_for(ud.drink, ud.fridge)
        if shelf is None:
            return "missing"
        ud.shelf = shelf
        return "found"


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = FetchDrinkWorld(task, seed=seed, fail_rate=fail_rate, variant=variant)
    believed = task.initial_facts
    robot = next(f[1] for f in believed if f[0] == "at")
    fridge, kitchen = next((f[1], f[2]) for f in believed if f[0] == "fridge-in")
    orders = [(g[1], g[2]) for g in task.goal_facts if g[0] == "served"]
    shelf_of = {f[1]: f[2] for f in believed if f[0] == "on"}
    room_of = {f[1]: f[2] for f in believed if f[0] == "person-at"}

    mission = smach.StateMachine(outcomes=OUTCOMES)
    mission.userdata.robot = robot
    mission.userdata.fridge = fridge
    here = next(f[2] for f in believed if f[0] == "at")
    with mission:
        for n, (person, drink) in enumerate(orders, start=1):
            last = n == len(orders)
            room = room_of[person]
            mission.userdata[f"drink_{n}"] = drink
            mission.userdata[f"shelf_{n}"] = shelf_of[drink]
            mission.userdata[f"person_{n}"] = person
            mission.userdata[f"room_{n}"] = room
            this_drink = {"drink": f"drink_{n}", "shelf": f"shelf_{n}"}
            smach.StateMachine.add(
                f"GO_TO_FRIDGE_{n}",
                go_to(world, here, kitchen),
                {"arrived": f"OPEN_FRIDGE_{n}", "failed": "aborted"},
            )
            smach.StateMachine.add(
                f"OPEN_FRIDGE_{n}",
                open_fridge_machine(world, robot, fridge),
                {"succeeded": f"FIND_DRINK_{n}"},
            )
            smach.StateMachine.add(
                f"FIND_DRINK_{n}",
                ScanShelves(world),
                {"found": f"PICK_{n}", "missing": "aborted"},
                remapping=this_drink,
            )
            smach.StateMachine.add(
                f"PICK_{n}",
                grasp_machine(world),
                {"held": f"CLOSE_FRIDGE_{n}", "slipped": "aborted"},
                remapping=this_drink,
            )
            smach.StateMachine.add(
                f"CLOSE_FRIDGE_{n}",
                close_fridge_machine(world, robot, fridge),
                {"succeeded": f"GO_TO_PERSON_{n}"},
            )
            smach.StateMachine.add(
                f"GO_TO_PERSON_{n}",
                go_to(world, kitchen, room),
                {"arrived": f"HAND_OVER_{n}", "failed": "aborted"},
            )
            smach.StateMachine.add(
                f"HAND_OVER_{n}",
                hand_over_machine(world, robot, drink, person, room),
                {"succeeded": "succeeded" if last else f"GO_TO_FRIDGE_{n + 1}"},
            )
            here = room
    return ScriptedMission(mission, world)
