"""The door_opening skills: one hand-written SMACH machine per PDDL action.

The behaviours (``open_door_behaviour``, ``pass_door_behaviour``,
``cross_behaviour``) read their arguments from userdata, so the same machines serve
the planned skills (which preset their userdata from the plan step) and the scripted
baseline (which feeds them from its route, see scripted.py).

A locked door is the interesting case: the latch does not retract when the handle
turns, the skill reports ``(unlocked door)`` false and ends ``locked``, which the
registry maps to ``aborted``; the executive then plans a route around the door.
"""

from __future__ import annotations

from collections.abc import Callable

import smach
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import SKILL_OUTCOMES, Report, WorldCall, fact, observe, skill_machine
from plan_bridge.skills.registry import SkillRegistry

from .world import DoorWorld

__all__ = [
    "build_skills",
    "cross_behaviour",
    "open_door_behaviour",
    "pass_door_behaviour",
    "setup",
]

OPEN_ATTEMPTS = 3


def _door_call(call: Callable[[str], bool], *, ok: str, failed: str) -> WorldCall:
    """One call on the door in userdata ``door``: ``ok`` if it worked, else ``failed``."""
    return WorldCall(lambda ud: call(ud.door), ok=ok, failed=failed, input_keys=["door"])


class ReleaseHandle(smach.State):
    """Open the gripper and back off the handle."""

    def __init__(self, world: DoorWorld) -> None:
        super().__init__(outcomes=["released"], input_keys=["door"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        self.world.release_handle(ud.door)
        return "released"


class CheckDoor(smach.State):
    """Look at the door (the laser sees the gap): report open or closed."""

    def __init__(self, world: DoorWorld) -> None:
        super().__init__(outcomes=["open", "closed"], input_keys=["door"], io_keys=["observations"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        is_open = self.world.holds("door-open", ud.door)
        observe(
            ud, (fact("door-open", ud.door), is_open), (fact("door-closed", ud.door), not is_open)
        )
        return "open" if is_open else "closed"


def open_attempt(world: DoorWorld) -> smach.StateMachine:
    """GRASP_HANDLE -> TURN_HANDLE -> PUSH_DOOR; a stuck door is released and retried."""
    attempt = smach.StateMachine(
        outcomes=["opened", "locked", "failed", "preempted"], input_keys=["door"]
    )
    with attempt:
        smach.StateMachine.add(
            "GRASP_HANDLE",
            _door_call(world.grasp_handle, ok="grasped", failed="slipped"),
            {"grasped": "TURN_HANDLE", "slipped": "failed"},
        )
        smach.StateMachine.add(
            "TURN_HANDLE",
            _door_call(world.turn_handle, ok="turned", failed="latched"),
            {"turned": "PUSH_DOOR", "latched": "RELEASE_LOCKED"},
        )
        smach.StateMachine.add(
            "PUSH_DOOR",
            _door_call(world.push_door, ok="opened", failed="stuck"),
            {"stuck": "RELEASE_STUCK"},
        )
        smach.StateMachine.add("RELEASE_STUCK", ReleaseHandle(world), {"released": "failed"})
        smach.StateMachine.add("RELEASE_LOCKED", ReleaseHandle(world), {"released": "locked"})
    return attempt


def open_door_behaviour(world: DoorWorld) -> smach.StateMachine:
    """Open the door in userdata ``door``: opened / locked / failed.

    ::

        FIND_HANDLE -> OPEN = Retry x3 [GRASP_HANDLE -> TURN_HANDLE -> PUSH_DOOR]
        OPEN --opened/failed--> CHECK_OPEN --open--> opened, --closed--> failed
             --locked--> REPORT_LOCKED (unlocked door: false) --> locked
    """
    sm = smach.StateMachine(
        outcomes=["opened", "locked", "failed", "preempted"],
        input_keys=["door", "observations"],
        output_keys=["observations"],
    )
    with sm:
        smach.StateMachine.add(
            "FIND_HANDLE",
            _door_call(world.find_handle, ok="found", failed="missing"),
            {"found": "OPEN", "missing": "failed"},
        )
        smach.StateMachine.add(
            "OPEN",
            smach.Retry.wrap(
                "ATTEMPT", open_attempt(world), attempts=OPEN_ATTEMPTS, retry_outcomes=["failed"]
            ),
            {"opened": "CHECK_OPEN", "failed": "CHECK_OPEN", "locked": "REPORT_LOCKED"},
        )
        smach.StateMachine.add(
            "CHECK_OPEN", CheckDoor(world), {"open": "opened", "closed": "failed"}
        )
        smach.StateMachine.add(
            "REPORT_LOCKED",
            Report(lambda ud: {fact("unlocked", ud.door): False}, "locked", ["door"]),
            {"locked": "locked"},
        )
    return sm


def pass_door_behaviour(world: DoorWorld) -> smach.StateMachine:
    """Drive through the open door: passed / failed (the door closer shut it first).

    ::

        CHECK_DOOR --open--> DRIVE_THROUGH --passed--> passed
                   --closed--> failed      --shut--> CHECK_SHUT --> failed
    """
    keys = ["robot", "door", "from_room", "to_room"]
    sm = smach.StateMachine(
        outcomes=["passed", "failed", "preempted"],
        input_keys=[*keys, "observations"],
        output_keys=["observations"],
    )
    with sm:
        smach.StateMachine.add(
            "CHECK_DOOR", CheckDoor(world), {"open": "DRIVE_THROUGH", "closed": "failed"}
        )
        smach.StateMachine.add(
            "DRIVE_THROUGH",
            WorldCall(
                lambda ud: world.pass_door(ud.robot, ud.door, ud.from_room, ud.to_room),
                ok="passed",
                failed="shut",
                input_keys=keys,
            ),
            {"shut": "CHECK_SHUT"},
        )
        smach.StateMachine.add(
            "CHECK_SHUT", CheckDoor(world), {"open": "failed", "closed": "failed"}
        )
    return sm


def cross_behaviour(world: DoorWorld) -> smach.State:
    """Drive through an open passage: crossed / failed."""
    return WorldCall(
        lambda ud: world.cross(ud.robot, ud.from_room, ud.to_room),
        ok="crossed",
        failed="failed",
        input_keys=["robot", "from_room", "to_room"],
    )


# -- skills: the behaviours with their arguments preset from the plan step ------------------


def move_skill(world: DoorWorld, robot: str, origin: str, destination: str) -> smach.StateMachine:
    sm = skill_machine(bind={"robot": robot, "from_room": origin, "to_room": destination})
    with sm:
        smach.StateMachine.add(
            "CROSS", cross_behaviour(world), {"crossed": "succeeded", "failed": "aborted"}
        )
    return sm


def open_door_skill(world: DoorWorld, robot: str, door: str) -> smach.StateMachine:
    """OPEN_DOOR; its ``locked`` outcome is mapped to ``aborted`` by the registry."""
    sm = skill_machine(bind={"robot": robot, "door": door}, outcomes=[*SKILL_OUTCOMES, "locked"])
    with sm:
        smach.StateMachine.add(
            "OPEN_DOOR",
            open_door_behaviour(world),
            {"opened": "succeeded", "locked": "locked", "failed": "aborted"},
        )
    return sm


def pass_door_skill(
    world: DoorWorld, robot: str, door: str, origin: str, destination: str
) -> smach.StateMachine:
    sm = skill_machine(
        bind={"robot": robot, "door": door, "from_room": origin, "to_room": destination}
    )
    with sm:
        smach.StateMachine.add(
            "PASS_DOOR", pass_door_behaviour(world), {"passed": "succeeded", "failed": "aborted"}
        )
    return sm


def build_skills(world: DoorWorld) -> SkillRegistry:
    """The registry binding every action of domain.pddl to its machine."""
    skills = SkillRegistry(simulated=True)
    skills.add("move", lambda r, a, b: move_skill(world, r, a, b))
    skills.add(
        "open-door",
        lambda r, d, a, b: open_door_skill(world, r, d),
        outcome_map={"locked": "aborted"},
    )
    skills.add("pass-door", lambda r, d, a, b: pass_door_skill(world, r, d, a, b))
    return skills


def setup(task: PlanningTask, *, seed: int, fail_rate: float, variant: str = "") -> MissionSetup:
    """The mission protocol of plan_bridge: skills acting on a fresh simulated world."""
    world = DoorWorld(task, seed=seed, fail_rate=fail_rate, variant=variant)
    return MissionSetup(skills=build_skills(world), world=world)
