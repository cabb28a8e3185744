"""Skills of the table-clearing mission: one SMACH machine per PDDL action.

Written the way the PR2 demo was: small states that each do one thing on the robot
(look, move the arm, close the gripper, check), put together in state machines with
local recovery, talking through userdata:

- ``pick``: DETECT (re-detects up to 3 times) -> GRASP_LOOP, a Retry around
  APPROACH -> GRASP -> VERIFY (up to 3 grasps while the object slips back onto the
  table),
- ``place``: CHECK_CART -> RELEASE_LOOP, a Retry around RELEASE -> CHECK_PLACED,
- ``push-cart``: GRIP_HANDLE -> PUSH, a Concurrence of DRIVE_CART and
  MONITOR_WHEELS (the monitor watches the wheel encoders and the bumper and ends the
  push on a jammed caster or an obstacle) -> RELEASE_HANDLE; a jam is handled by
  BACK_UP and pushing again, an obstacle is reported as a blocked passage,
- ``move``: DRIVE_BASE -> LOCALIZE.

Each machine reads its parameters (robot, item, spot, cart, ...) from userdata. For a
plan step the factory binds them in the machine's own userdata; the scripted
baseline (scripted.py) feeds them through remapping instead. Every state reports what
it saw as ``observations`` (fact -> true/false), so the executive's belief follows
the world and it can replan.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import smach
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import RobotState, observe, skill_machine
from plan_bridge.skills.registry import SkillRegistry

from .world import CartRun, TableWorld

__all__ = [
    "build_skills",
    "move_machine",
    "pick_machine",
    "place_machine",
    "push_machine",
    "setup",
]

OBS = "observations"
#: Real seconds the cart drive holds still waiting for the monitor (a safety net:
#: the monitor answers within microseconds; this only ends a broken run).
HOLD_LIMIT_S = 10.0
#: Pushes a jammed cart gets (backing up between them) before the skill gives up.
PUSH_ATTEMPTS = 3


# -- pick ------------------------------------------------------------------------------------
class Detect(RobotState[TableWorld]):
    """Look for the object with the head camera; write where it lies (``object_spot``)."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            world,
            ["found", "out_of_reach", "not_seen"],
            input_keys=["robot", "item", "expected_spot"],
            output_keys=["object_spot"],
        )

    def act(self, ud: smach.UserData) -> str:
        spot = self.world.look(ud.robot, ud.item)
        if spot is None:
            return "not_seen"
        ud.object_spot = spot
        if spot != ud.expected_spot:
            observe(ud, (("item-at", ud.item, ud.expected_spot), False))
        observe(ud, (("item-at", ud.item, spot), True))
        if not self.world.reachable(ud.robot, spot):
            return "out_of_reach"
        return "found"


class Approach(RobotState[TableWorld]):
    """Move the arm to the pre-grasp pose above the object."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["ready", "out_of_reach"], input_keys=["robot", "target_spot"])

    def act(self, ud: smach.UserData) -> str:
        return "ready" if self.world.approach(ud.robot, ud.target_spot) else "out_of_reach"


class Grasp(RobotState[TableWorld]):
    """Close the gripper around the object."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["closed"], input_keys=["robot", "item", "target_spot"])

    def act(self, ud: smach.UserData) -> str:
        self.world.grasp(ud.robot, ud.item, ud.target_spot)
        return "closed"


class VerifyGrasp(RobotState[TableWorld]):
    """Check the gripper's force sensor; if empty, look where the object went."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            world, ["picked", "slipped", "dropped"], input_keys=["robot", "item", "target_spot"]
        )

    def act(self, ud: smach.UserData) -> str:
        robot, item, spot = ud.robot, ud.item, ud.target_spot
        if self.world.held_by(robot) == item:
            observe(
                ud,
                (("holding", robot, item), True),
                (("hand-empty", robot), False),
                (("item-at", item, spot), False),
            )
            return "picked"
        observe(ud, (("holding", robot, item), False), (("hand-empty", robot), True))
        seen = self.world.look(robot, item)
        if seen == spot:
            observe(ud, (("item-at", item, spot), True))
            return "slipped"
        observe(ud, (("item-at", item, spot), False))
        if seen is not None:
            observe(ud, (("item-at", item, seen), True))
        return "dropped"


def pick_machine(world: TableWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """DETECT -> GRASP_LOOP(APPROACH -> GRASP -> VERIFY); keys robot, item, spot."""
    sm = skill_machine(["robot", "item", "spot"], bind)
    detect = smach.Retry.wrap("LOOK", Detect(world), attempts=3, retry_outcomes=["not_seen"])
    attempt = smach.StateMachine(
        outcomes=["picked", "slipped", "dropped", "out_of_reach", "preempted"],
        input_keys=["robot", "item", "target_spot", OBS],
        output_keys=[OBS],
    )
    with attempt:
        smach.StateMachine.add("APPROACH", Approach(world), transitions={"ready": "GRASP"})
        smach.StateMachine.add("GRASP", Grasp(world), transitions={"closed": "VERIFY"})
        smach.StateMachine.add("VERIFY", VerifyGrasp(world))
    grasp_loop = smach.Retry.wrap("ATTEMPT", attempt, attempts=3, retry_outcomes=["slipped"])
    with sm:
        smach.StateMachine.add(
            "DETECT",
            detect,
            transitions={"found": "GRASP_LOOP", "out_of_reach": "aborted", "not_seen": "aborted"},
            remapping={"expected_spot": "spot", "object_spot": "object_spot"},
        )
        smach.StateMachine.add(
            "GRASP_LOOP",
            grasp_loop,
            transitions={
                "picked": "succeeded",
                "slipped": "aborted",
                "dropped": "aborted",
                "out_of_reach": "aborted",
            },
            remapping={"target_spot": "object_spot"},
        )
    return sm


# -- place -----------------------------------------------------------------------------------
class CheckCart(RobotState[TableWorld]):
    """Is the cart next to the robot (the tray's fiducial in view)?"""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["present", "missing"], input_keys=["robot", "cart"])

    def act(self, ud: smach.UserData) -> str:
        here = self.world.robot_location(ud.robot)
        there = self.world.cart_location(ud.cart)
        if there is not None:
            observe(ud, (("cart-at", ud.cart, there), True))
        if here is not None and here != there:
            observe(ud, (("cart-at", ud.cart, here), False))
        return "present" if here is not None and here == there else "missing"


class Release(RobotState[TableWorld]):
    """Move the object above the cart's tray and open the gripper."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["released"], input_keys=["robot", "item", "cart"])

    def act(self, ud: smach.UserData) -> str:
        self.world.release_on_cart(ud.robot, ud.item, ud.cart)
        return "released"


class CheckPlaced(RobotState[TableWorld]):
    """Is the object on the tray and the gripper empty?"""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            world, ["on_cart", "still_held", "lost"], input_keys=["robot", "item", "cart"]
        )

    def act(self, ud: smach.UserData) -> str:
        robot, item, cart = ud.robot, ud.item, ud.cart
        on_cart = self.world.is_on_cart(item, cart)
        held = self.world.held_by(robot) == item
        observe(
            ud,
            (("on-cart", item, cart), on_cart),
            (("holding", robot, item), held),
            (("hand-empty", robot), not held),
        )
        if on_cart:
            return "on_cart"
        return "still_held" if held else "lost"


def place_machine(world: TableWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """CHECK_CART -> RELEASE_LOOP(RELEASE -> CHECK_PLACED); keys robot, item, cart."""
    sm = skill_machine(["robot", "item", "cart"], bind)
    attempt = smach.StateMachine(
        outcomes=["on_cart", "still_held", "lost", "preempted"],
        input_keys=["robot", "item", "cart", OBS],
        output_keys=[OBS],
    )
    with attempt:
        smach.StateMachine.add("RELEASE", Release(world), transitions={"released": "CHECK_PLACED"})
        smach.StateMachine.add("CHECK_PLACED", CheckPlaced(world))
    with sm:
        smach.StateMachine.add(
            "CHECK_CART",
            CheckCart(world),
            transitions={"present": "RELEASE_LOOP", "missing": "aborted"},
        )
        smach.StateMachine.add(
            "RELEASE_LOOP",
            smach.Retry.wrap("ATTEMPT", attempt, attempts=2, retry_outcomes=["still_held"]),
            transitions={"on_cart": "succeeded", "still_held": "aborted", "lost": "aborted"},
        )
    return sm


# -- push-cart -------------------------------------------------------------------------------
class GripHandle(RobotState[TableWorld]):
    """Put both grippers on the cart's handle; start the run (``cart_run``)."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            world,
            ["gripped", "failed"],
            input_keys=["robot", "cart", "source", "target"],
            output_keys=["cart_run"],
        )

    def act(self, ud: smach.UserData) -> str:
        if not self.world.grip_handle(ud.robot, ud.cart):
            here = self.world.robot_location(ud.robot)
            there = self.world.cart_location(ud.cart)
            observe(ud, (("robot-at", ud.robot, ud.source), here == ud.source))
            observe(ud, (("cart-at", ud.cart, ud.source), there == ud.source))
            return "failed"
        ud.cart_run = self.world.start_push(ud.robot, ud.cart, ud.source, ud.target)
        return "gripped"


class DriveCart(smach.State):
    """Drive the base with the cart, segment by segment; hold still when it cannot move."""

    def __init__(self, world: TableWorld) -> None:
        # cart_run is an io key: the world updates the run object in place.
        super().__init__(
            outcomes=["arrived", "aborted", "preempted"],
            input_keys=["robot", "cart"],
            io_keys=["cart_run"],
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        run: CartRun = ud.cart_run
        while True:
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            status = self.world.push_segment(ud.robot, ud.cart, run)
            if status == "arrived":
                return "arrived"
            if status != "moving":
                # The controller stops the wheels; the monitor decides what happens next.
                if self.preempt_event.wait(HOLD_LIMIT_S):
                    self.service_preempt()
                    return "preempted"
                return "aborted"


class MonitorWheels(smach.State):
    """Watch the wheel encoders and the bumper while the cart is pushed."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            outcomes=["wheels_stalled", "obstacle", "preempted"], input_keys=["cart_run"]
        )
        self.world = world
        self._run: CartRun | None = None

    def execute(self, ud: smach.UserData) -> str:
        run: CartRun = ud.cart_run
        self._run = run
        changed = run.changed
        try:
            while True:
                if run.status == "stalled":
                    return "wheels_stalled"
                if run.status == "obstacle":
                    return "obstacle"
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                changed.wait()
                changed.clear()
        finally:
            self._run = None

    def request_preempt(self) -> None:
        super().request_preempt()
        run = self._run
        if run is not None:
            run.changed.set()


def _push_outcome(outcomes: Mapping[str, str | None]) -> str:
    if outcomes.get("DRIVE_CART") == "arrived":
        return "arrived"
    monitor = outcomes.get("MONITOR_WHEELS")
    if monitor == "wheels_stalled":
        return "stuck"
    if monitor == "obstacle":
        return "blocked"
    if monitor == "preempted" and outcomes.get("DRIVE_CART") == "preempted":
        return "preempted"
    return "aborted"


class BackUp(RobotState[TableWorld]):
    """Pull the cart back to free a jammed caster; give up after PUSH_ATTEMPTS pushes."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(
            world,
            ["retry", "give_up"],
            input_keys=["cart_run", "pushes"],
            output_keys=["cart_run", "pushes"],
        )

    def act(self, ud: smach.UserData) -> str:
        pushes = ud.pushes + 1
        ud.pushes = pushes
        if pushes >= PUSH_ATTEMPTS:
            return "give_up"
        self.world.back_up(ud.cart_run)
        return "retry"


class ReportBlocked(RobotState[TableWorld]):
    """The laser sees the passage ahead blocked: tell the planner (both directions)."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["reported"], input_keys=["robot", "cart", "source", "target"])

    def act(self, ud: smach.UserData) -> str:
        source, target = ud.source, ud.target
        observe(
            ud,
            (("clear", source, target), False),
            (("clear", target, source), False),
            (("robot-at", ud.robot, source), True),
            (("cart-at", ud.cart, source), True),
        )
        return "reported"


class ReleaseHandle(RobotState[TableWorld]):
    """Let go of the handle and localise robot and cart."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["released"], input_keys=["robot", "cart", "source", "target"])

    def act(self, ud: smach.UserData) -> str:
        here = self.world.robot_location(ud.robot)
        there = self.world.cart_location(ud.cart)
        for location in (ud.source, ud.target):
            observe(
                ud,
                (("robot-at", ud.robot, location), here == location),
                (("cart-at", ud.cart, location), there == location),
            )
        return "released"


def push_machine(world: TableWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """GRIP_HANDLE -> PUSH(DRIVE_CART || MONITOR_WHEELS) -> RELEASE_HANDLE, with BACK_UP."""
    sm = skill_machine(["robot", "cart", "source", "target"], bind)
    sm.userdata.pushes = 0
    push = smach.Concurrence(
        outcomes=["arrived", "stuck", "blocked", "aborted", "preempted"],
        default_outcome="aborted",
        input_keys=["robot", "cart", "cart_run"],
        outcome_cb=_push_outcome,
        # Whoever finishes first (the drive arriving, the monitor raising an alarm)
        # ends the push: preempt the other.
        child_termination_cb=lambda outcomes: True,
    )
    with push:
        smach.Concurrence.add("DRIVE_CART", DriveCart(world))
        smach.Concurrence.add("MONITOR_WHEELS", MonitorWheels(world))
    with sm:
        smach.StateMachine.add(
            "GRIP_HANDLE", GripHandle(world), transitions={"gripped": "PUSH", "failed": "aborted"}
        )
        smach.StateMachine.add(
            "PUSH",
            push,
            transitions={
                "arrived": "RELEASE_HANDLE",
                "stuck": "BACK_UP",
                "blocked": "REPORT_BLOCKED",
                "aborted": "aborted",
            },
        )
        smach.StateMachine.add(
            "BACK_UP", BackUp(world), transitions={"retry": "PUSH", "give_up": "aborted"}
        )
        smach.StateMachine.add(
            "REPORT_BLOCKED", ReportBlocked(world), transitions={"reported": "aborted"}
        )
        smach.StateMachine.add(
            "RELEASE_HANDLE", ReleaseHandle(world), transitions={"released": "succeeded"}
        )
    return sm


# -- move ------------------------------------------------------------------------------------
class DriveBase(RobotState[TableWorld]):
    """Drive the base (without the cart) to the goal location."""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["arrived", "failed"], input_keys=["robot", "source", "target"])

    def act(self, ud: smach.UserData) -> str:
        return "arrived" if self.world.walk(ud.robot, ud.source, ud.target) else "failed"


class Localize(RobotState[TableWorld]):
    """Where is the robot now (AMCL)?"""

    def __init__(self, world: TableWorld) -> None:
        super().__init__(world, ["at_goal", "elsewhere"], input_keys=["robot", "source", "target"])

    def act(self, ud: smach.UserData) -> str:
        here = self.world.robot_location(ud.robot)
        observe(
            ud,
            (("robot-at", ud.robot, ud.source), here == ud.source),
            (("robot-at", ud.robot, ud.target), here == ud.target),
        )
        return "at_goal" if here == ud.target else "elsewhere"


def move_machine(world: TableWorld, bind: Mapping[str, Any] | None = None) -> smach.StateMachine:
    """DRIVE_BASE -> LOCALIZE; keys robot, source, target."""
    sm = skill_machine(["robot", "source", "target"], bind)
    with sm:
        smach.StateMachine.add(
            "DRIVE_BASE",
            DriveBase(world),
            transitions={"arrived": "LOCALIZE", "failed": "LOCALIZE"},
        )
        smach.StateMachine.add(
            "LOCALIZE",
            Localize(world),
            transitions={"at_goal": "succeeded", "elsewhere": "aborted"},
        )
    return sm


# -- the registry ----------------------------------------------------------------------------
def build_skills(world: TableWorld) -> SkillRegistry:
    """One skill per PDDL action, bound to ``world``."""
    skills = SkillRegistry(simulated=True)

    @skills.register("move")
    def move(robot: str, source: str, target: str) -> smach.State:
        return move_machine(world, {"robot": robot, "source": source, "target": target})

    @skills.register("pick")
    def pick(robot: str, item: str, spot: str, location: str) -> smach.State:
        return pick_machine(world, {"robot": robot, "item": item, "spot": spot})

    @skills.register("place")
    def place(robot: str, item: str, cart: str, location: str) -> smach.State:
        return place_machine(world, {"robot": robot, "item": item, "cart": cart})

    @skills.register("push-cart")
    def push_cart(robot: str, cart: str, source: str, target: str) -> smach.State:
        return push_machine(
            world, {"robot": robot, "cart": cart, "source": source, "target": target}
        )

    return skills


def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup:
    """The mission's world and skills for one run (``plan-bridge run domains/table_clearing``)."""
    world = TableWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=build_skills(world), world=world)
