"""Skills of the two-robot delivery mission: one SMACH machine per PDDL action.

- ``move``: CHECK_DOOR -> DRIVE (a Retry: a person in the way stalls an attempt) ->
  CHECK_LOAD (is the carried item still in the gripper?); a blocked door is reported
  as not passable (both ways) so that the executive plans another route,
- ``pick``: DETECT -> GRASP_LOOP, a Retry around GRASP -> VERIFY (the item may slip
  back onto the shelf),
- ``drop``: RELEASE_LOOP, a Retry around RELEASE -> CHECK_RELEASED.

Each machine reads its parameters from userdata: bound in its own userdata for a
plan step, fed through remapping by the scripted baseline. States report what they
saw as ``observations``. The mission runs with ``MissionSetup(concurrent=True)``:
the steps of r1 and r2 run side by side in a smach.Concurrence (the world is
thread-safe and deterministic per seed, see world.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import smach
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import RobotState, observe, skill_machine
from plan_bridge.skills.registry import SkillRegistry

from .world import DeliveryWorld

__all__ = ["build_skills", "drop_machine", "move_machine", "pick_machine", "setup"]

OBS = "observations"


# -- move ------------------------------------------------------------------------------------
class CheckGripper(RobotState[DeliveryWorld]):
    """What does the robot carry as it sets off (``carrying``: an item or None)?"""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["checked"], input_keys=["robot"], output_keys=["carrying"])

    def act(self, ud: smach.UserData) -> str:
        ud.carrying = self.world.held_by(ud.robot)
        return "checked"


class CheckDoor(RobotState[DeliveryWorld]):
    """Look at the door ahead; report a blocked one as not passable, both ways."""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["open", "blocked"], input_keys=["robot", "source", "target"])

    def act(self, ud: smach.UserData) -> str:
        if self.world.door_open(ud.robot, ud.source, ud.target):
            return "open"
        observe(
            ud,
            (("passable", ud.source, ud.target), False),
            (("passable", ud.target, ud.source), False),
        )
        return "blocked"


class Drive(RobotState[DeliveryWorld]):
    """Drive through the door to the next room."""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(
            world, ["arrived", "stalled", "failed"], input_keys=["robot", "source", "target"]
        )

    def act(self, ud: smach.UserData) -> str:
        return self.world.drive(ud.robot, ud.source, ud.target)


class CheckLoad(RobotState[DeliveryWorld]):
    """Localise, and check that the carried item is still in the gripper."""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(
            world, ["ok", "lost"], input_keys=["robot", "source", "target", "carrying"]
        )

    def act(self, ud: smach.UserData) -> str:
        robot = ud.robot
        here = self.world.location(robot)
        observe(
            ud,
            (("at", robot, ud.source), here == ud.source),
            (("at", robot, ud.target), here == ud.target),
        )
        carried: str | None = ud.carrying
        if carried is None:
            return "ok" if here == ud.target else "lost"
        held = self.world.held_by(robot)
        if held == carried:
            return "ok" if here == ud.target else "lost"
        # The item fell off on the way out: it lies in the room the robot left.
        observe(
            ud,
            (("holding", robot, carried), False),
            (("hand-empty", robot), held is None),
            (("item-at", carried, ud.source), True),
        )
        return "ok" if here == ud.target else "lost"


def move_machine(world: DeliveryWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """CHECK_GRIPPER -> CHECK_DOOR -> DRIVE (Retry) -> CHECK_LOAD; keys robot, source, target."""
    sm = skill_machine(["robot", "source", "target"], bind)
    with sm:
        smach.StateMachine.add(
            "CHECK_GRIPPER", CheckGripper(world), transitions={"checked": "CHECK_DOOR"}
        )
        smach.StateMachine.add(
            "CHECK_DOOR", CheckDoor(world), transitions={"open": "DRIVE", "blocked": "aborted"}
        )
        smach.StateMachine.add(
            "DRIVE",
            smach.Retry.wrap("GO", Drive(world), attempts=3, retry_outcomes=["stalled"]),
            transitions={"arrived": "CHECK_LOAD", "stalled": "CHECK_LOAD", "failed": "CHECK_LOAD"},
        )
        smach.StateMachine.add(
            "CHECK_LOAD", CheckLoad(world), transitions={"ok": "succeeded", "lost": "aborted"}
        )
    return sm


# -- pick ------------------------------------------------------------------------------------
class Detect(RobotState[DeliveryWorld]):
    """Find the item on the shelves of this room."""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["found", "missing"], input_keys=["robot", "item", "room"])

    def act(self, ud: smach.UserData) -> str:
        seen = self.world.sees(ud.robot, ud.item)
        observe(ud, (("item-at", ud.item, ud.room), seen))
        return "found" if seen else "missing"


class Grasp(RobotState[DeliveryWorld]):
    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["closed"], input_keys=["robot", "item"])

    def act(self, ud: smach.UserData) -> str:
        self.world.grasp(ud.robot, ud.item)
        return "closed"


class VerifyGrasp(RobotState[DeliveryWorld]):
    """Is the item in the gripper (force sensor)?"""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["picked", "slipped"], input_keys=["robot", "item", "room"])

    def act(self, ud: smach.UserData) -> str:
        robot, item = ud.robot, ud.item
        held = self.world.held_by(robot) == item
        observe(
            ud,
            (("holding", robot, item), held),
            (("hand-empty", robot), not held),
            (("item-at", item, ud.room), not held),
        )
        return "picked" if held else "slipped"


def pick_machine(world: DeliveryWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """DETECT -> GRASP_LOOP(GRASP -> VERIFY); keys robot, item, room."""
    sm = skill_machine(["robot", "item", "room"], bind)
    attempt = smach.StateMachine(
        outcomes=["picked", "slipped", "preempted"],
        input_keys=["robot", "item", "room", OBS],
        output_keys=[OBS],
    )
    with attempt:
        smach.StateMachine.add("GRASP", Grasp(world), transitions={"closed": "VERIFY"})
        smach.StateMachine.add("VERIFY", VerifyGrasp(world))
    with sm:
        smach.StateMachine.add(
            "DETECT", Detect(world), transitions={"found": "GRASP_LOOP", "missing": "aborted"}
        )
        smach.StateMachine.add(
            "GRASP_LOOP",
            smach.Retry.wrap("ATTEMPT", attempt, attempts=2, retry_outcomes=["slipped"]),
            transitions={"picked": "succeeded", "slipped": "aborted"},
        )
    return sm


# -- drop ------------------------------------------------------------------------------------
class Release(RobotState[DeliveryWorld]):
    """Put the item on the desk and open the gripper."""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(world, ["released"], input_keys=["robot", "item"])

    def act(self, ud: smach.UserData) -> str:
        self.world.release(ud.robot, ud.item)
        return "released"


class CheckReleased(RobotState[DeliveryWorld]):
    """Is the gripper empty and the item on the desk (camera)?"""

    def __init__(self, world: DeliveryWorld) -> None:
        super().__init__(
            world, ["delivered", "still_held", "lost"], input_keys=["robot", "item", "room"]
        )

    def act(self, ud: smach.UserData) -> str:
        robot, item = ud.robot, ud.item
        held = self.world.held_by(robot) == item
        on_desk = not held and self.world.sees(robot, item)
        observe(
            ud,
            (("holding", robot, item), held),
            (("hand-empty", robot), not held),
            (("item-at", item, ud.room), on_desk),
        )
        if held:
            return "still_held"
        return "delivered" if on_desk else "lost"


def drop_machine(world: DeliveryWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """RELEASE_LOOP(RELEASE -> CHECK_RELEASED); keys robot, item, room."""
    sm = skill_machine(["robot", "item", "room"], bind)
    attempt = smach.StateMachine(
        outcomes=["delivered", "still_held", "lost", "preempted"],
        input_keys=["robot", "item", "room", OBS],
        output_keys=[OBS],
    )
    with attempt:
        smach.StateMachine.add(
            "RELEASE", Release(world), transitions={"released": "CHECK_RELEASED"}
        )
        smach.StateMachine.add("CHECK_RELEASED", CheckReleased(world))
    with sm:
        smach.StateMachine.add(
            "RELEASE_LOOP",
            smach.Retry.wrap("ATTEMPT", attempt, attempts=2, retry_outcomes=["still_held"]),
            transitions={"delivered": "succeeded", "still_held": "aborted", "lost": "aborted"},
        )
    return sm


# -- the registry ----------------------------------------------------------------------------
def build_skills(world: DeliveryWorld) -> SkillRegistry:
    """One skill per PDDL action, bound to ``world``."""
    skills = SkillRegistry(simulated=True)

    @skills.register("move")
    def move(robot: str, source: str, target: str) -> smach.State:
        return move_machine(world, {"robot": robot, "source": source, "target": target})

    @skills.register("pick")
    def pick(robot: str, item: str, room: str) -> smach.State:
        return pick_machine(world, {"robot": robot, "item": item, "room": room})

    @skills.register("drop")
    def drop(robot: str, item: str, room: str) -> smach.State:
        return drop_machine(world, {"robot": robot, "item": item, "room": room})

    return skills


def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup:
    """World and skills for one run; the two robots' steps run concurrently."""
    world = DeliveryWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=build_skills(world), world=world, concurrent=True)
