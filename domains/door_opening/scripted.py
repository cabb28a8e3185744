"""door_opening written by hand: one SMACH machine with explicit recovery, no planner.

The author took the building plan, wrote down the shortest route from the start to
the goal room and ONE detour that uses none of the route's doors, and hard-coded the
recoveries they anticipated:

* handle slips and stuck doors: the open behaviour's own three attempts, and if the
  door still will not open, the whole behaviour once more;
* a door closer that swings the door shut in front of the robot: open it once more;
* a locked door: drive back to the start and follow the detour.

A locked door on the detour as well, or a door that will not open after three
attempts, ends the mission ``aborted``. The machine::

    FOLLOW_ROUTE --arrived--> succeeded
                 --locked--> RETURN_TO_START -> FOLLOW_DETOUR --arrived--> succeeded
    FOLLOW_X = Iterator over joints [ NEXT_JOINT --door--> OPEN_DOOR -> PASS_DOOR
                                      (--failed--> OPEN_AGAIN; --shut--> REOPEN_DOOR
                                       -> PASS_AGAIN)
                                      --passage--> CROSS ] -> MARK_REACHED
"""

from __future__ import annotations

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import PlanningTask

from .skills import cross_behaviour, open_door_behaviour, pass_door_behaviour
from .world import DoorWorld, Joint

__all__ = ["follow_route", "scripted"]


def follow_route(world: DoorWorld, route: list[Joint] | None) -> smach.Iterator:
    """Follow a fixed route joint by joint; ``reached`` lists the joints passed."""
    follow = smach.Iterator(
        outcomes=["arrived", "locked", "failed", "preempted"],
        input_keys=["robot", "observations"],
        output_keys=["reached", "observations"],
        it=list(route or []),
        it_label="joint",
        exhausted_outcome="arrived" if route is not None else "failed",
    )
    follow.userdata.reached = []
    leg = smach.StateMachine(
        outcomes=["next", "locked", "failed", "preempted"],
        input_keys=["robot", "joint", "reached", "observations"],
        output_keys=["reached", "observations"],
    )

    @smach.cb_interface(
        outcomes=["door", "passage"],
        input_keys=["joint"],
        output_keys=["from_room", "to_room", "door"],
    )
    def next_joint(ud: smach.UserData) -> str:
        ud.from_room, ud.to_room, ud.door = ud.joint
        return "passage" if ud.joint[2] is None else "door"

    @smach.cb_interface(outcomes=["next"], input_keys=["joint"], io_keys=["reached"])
    def mark_reached(ud: smach.UserData) -> str:
        ud.reached = [*ud.reached, ud.joint]
        return "next"

    with leg:
        smach.StateMachine.add(
            "NEXT_JOINT", smach.CBState(next_joint), {"door": "OPEN_DOOR", "passage": "CROSS"}
        )
        smach.StateMachine.add("CROSS", cross_behaviour(world), {"crossed": "MARK_REACHED"})
        smach.StateMachine.add(
            "OPEN_DOOR", open_door_behaviour(world), {"opened": "PASS_DOOR", "failed": "OPEN_AGAIN"}
        )
        smach.StateMachine.add("OPEN_AGAIN", open_door_behaviour(world), {"opened": "PASS_DOOR"})
        smach.StateMachine.add(
            "PASS_DOOR",
            pass_door_behaviour(world),
            {"passed": "MARK_REACHED", "failed": "REOPEN_DOOR"},
        )
        smach.StateMachine.add("REOPEN_DOOR", open_door_behaviour(world), {"opened": "PASS_AGAIN"})
        smach.StateMachine.add("PASS_AGAIN", pass_door_behaviour(world), {"passed": "MARK_REACHED"})
        smach.StateMachine.add("MARK_REACHED", smach.CBState(mark_reached))
    with follow:
        smach.Iterator.set_contained_state("LEG", leg, loop_outcomes=["next"])
    return follow


class ReturnToStart(smach.State):
    """Drive back through the joints just passed (their doors still stand open)."""

    def __init__(self, world: DoorWorld) -> None:
        super().__init__(outcomes=["returned", "failed"], input_keys=["robot", "reached"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        for origin, destination, door in reversed(ud.reached):
            if door is None:
                moved = self.world.cross(ud.robot, destination, origin)
            else:
                moved = self.world.pass_door(ud.robot, door, destination, origin)
            if not moved:
                return "failed"
        return "returned"


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = DoorWorld(task, seed=seed, fail_rate=fail_rate, variant=variant)
    robot = next(f[1] for f in task.initial_facts if f[0] == "at")
    goal = world.goal_rooms[0]
    route = world.joints(world.start, goal)
    detour = world.joints(world.start, goal, avoid_doors={j[2] for j in route or [] if j[2]})
    mission = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    mission.userdata.robot = robot
    mission.userdata.observations = {}
    with mission:
        smach.StateMachine.add(
            "FOLLOW_ROUTE",
            follow_route(world, route),
            {"arrived": "succeeded", "locked": "RETURN_TO_START", "failed": "aborted"},
        )
        smach.StateMachine.add(
            "RETURN_TO_START",
            ReturnToStart(world),
            {"returned": "FOLLOW_DETOUR", "failed": "aborted"},
        )
        smach.StateMachine.add(
            "FOLLOW_DETOUR",
            follow_route(world, detour),
            {"arrived": "succeeded", "locked": "aborted", "failed": "aborted"},
        )
    return ScriptedMission(mission, world)
