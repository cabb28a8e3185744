"""The recharge skills: SMACH machines per PDDL action, with a battery monitor.

Every drive runs in a ``smach.Concurrence`` next to a battery monitor::

    DRIVE_WITH_MONITOR = Concurrence [ DRIVE_ROUTE | MONITOR_BATTERY ]
        any child finishing preempts the other;
        DRIVE_ROUTE arrived                   -> arrived
        MONITOR_BATTERY low (drive preempted) -> battery_low
        otherwise                             -> failed

When the power board raises LOW, the monitor wakes, the Concurrence preempts the
drive, the robot stops at the nearer end of the corridor, and the skill reports
``(battery-low r)`` with the robot's room, so the executive replans: go to the
charger, plug in, charge, unplug, and resume the deliveries.

The drive outcome wins over the monitor's (``outcome_cb``): the world's state alone
decides the result, never which thread happened to run first, so seeded runs are
reproducible. The behaviours read their arguments from userdata and are shared with
the scripted baseline (scripted.py).
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable

import smach
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import WorldCall, fact, observe, skill_machine
from plan_bridge.skills.registry import SkillRegistry

from .world import RechargeWorld

__all__ = [
    "BatteryMonitor",
    "DriveRoute",
    "build_skills",
    "dock_behaviour",
    "drive_with_monitor",
    "plug_in_behaviour",
    "setup",
]

PLUG_ATTEMPTS = 3
GRASP_ATTEMPTS = 2
#: Real seconds a held drive waits for the monitor's preempt before giving up; the
#: monitor answers in microseconds, this only bounds a run without a monitor.
HOLD_TIMEOUT = 5.0


class DriveRoute(smach.State):
    """Drive ``route`` (a list of rooms) corridor by corridor, segment by segment.

    Outcomes: ``arrived``; ``halted`` (the base refused to move: battery empty, or
    held on LOW with nobody preempting); ``preempted`` (stopped at the nearer end).
    """

    def __init__(self, world: RechargeWorld, *, docking: bool = False) -> None:
        super().__init__(outcomes=["arrived", "halted", "preempted"], input_keys=["robot", "route"])
        self.world = world
        self.docking = docking

    def execute(self, ud: smach.UserData) -> str:
        world, robot = self.world, ud.robot
        route = list(ud.route or [])
        if not route:
            return "halted"
        for origin, destination in itertools.pairwise(route):
            if not world.start_drive(robot, origin, destination, docking=self.docking):
                return "halted"
            while True:
                if self.preempt_requested():
                    world.stop_drive(robot)
                    self.service_preempt()
                    return "preempted"
                status = world.drive_step(robot)
                if status == "arrived":
                    break
                if status == "dead":
                    world.stop_drive(robot)
                    return "halted"
                # Held on LOW: wait for the battery monitor to preempt us.
                if status == "held" and not self.sleep(HOLD_TIMEOUT):
                    world.stop_drive(robot)
                    return "halted"
        return "arrived"


class BatteryMonitor(smach.State):
    """Wait until the power board raises LOW (``low``) or a preempt (``preempted``)."""

    def __init__(self, world: RechargeWorld) -> None:
        super().__init__(outcomes=["low", "preempted"])
        self.world = world
        self._wake: threading.Event | None = None

    def request_preempt(self) -> None:
        super().request_preempt()
        wake = self._wake
        if wake is not None:
            wake.set()

    def execute(self, ud: smach.UserData) -> str:
        wake = threading.Event()
        self._wake = wake
        unsubscribe = self.world.on_battery_low(wake.set)
        try:
            while True:
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                if self.world.battery_low():
                    return "low"
                wake.wait(1.0)
                wake.clear()
        finally:
            unsubscribe()
            self._wake = None


def _drive_outcome(outcomes: dict[str, str | None]) -> str:
    if outcomes.get("DRIVE_ROUTE") == "arrived":
        return "arrived"
    if outcomes.get("MONITOR_BATTERY") == "low":
        return "battery_low"
    if outcomes.get("DRIVE_ROUTE") == "preempted":
        return "preempted"
    return "failed"


def drive_with_monitor(world: RechargeWorld) -> smach.Concurrence:
    """DRIVE_ROUTE next to MONITOR_BATTERY: arrived / battery_low / failed / preempted."""
    concurrence = smach.Concurrence(
        outcomes=["arrived", "battery_low", "failed", "preempted"],
        default_outcome="failed",
        input_keys=["robot", "route"],
        outcome_cb=_drive_outcome,
        child_termination_cb=lambda outcomes: True,  # either one finishing ends both
    )
    with concurrence:
        smach.Concurrence.add("DRIVE_ROUTE", DriveRoute(world))
        smach.Concurrence.add("MONITOR_BATTERY", BatteryMonitor(world))
    return concurrence


class ObserveRobot(smach.State):
    """Report where the robot is, what it holds and its battery state; return ``outcome``."""

    def __init__(self, world: RechargeWorld, outcome: str) -> None:
        super().__init__(outcomes=[outcome], input_keys=["robot"], io_keys=["observations"])
        self.world = world
        self.outcome = outcome

    def execute(self, ud: smach.UserData) -> str:
        robot, world = ud.robot, self.world
        low = world.battery_low()
        seen = {fact("battery-low", robot): low, fact("battery-ok", robot): not low}
        here = world.room_of(robot)
        seen.update(
            {fact("at", robot, room): room == here for room in world.task.objects_of_type("room")}
        )
        seen[fact("plugged", robot)] = world.holds("plugged", robot)
        seen[fact("unplugged", robot)] = world.holds("unplugged", robot)
        observe(ud, *seen.items())
        return self.outcome


class PlanRoute(smach.State):
    """The navigation stack's global planner: a route from here to ``destination``."""

    def __init__(self, world: RechargeWorld) -> None:
        super().__init__(
            outcomes=["planned", "unreachable"],
            input_keys=["robot", "destination"],
            output_keys=["route"],
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        route = self.world.route(self.world.room_of(ud.robot), ud.destination)
        ud.route = route
        return "planned" if route else "unreachable"


def _robot_call(call: Callable[[str], bool], *, ok: str, failed: str) -> WorldCall:
    """One call for the robot in userdata ``robot``: ``ok`` if it worked, else ``failed``."""
    return WorldCall(
        lambda ud: call(ud.robot), ok=ok, failed=failed, input_keys=["robot"], preemptable=False
    )


def dock_behaviour(world: RechargeWorld) -> smach.StateMachine:
    """PLAN_ROUTE to ``destination`` -> DOCK (low-power docking mode, no monitor)."""
    sm = smach.StateMachine(
        outcomes=["docked", "failed", "preempted"], input_keys=["robot", "destination"]
    )
    with sm:
        smach.StateMachine.add(
            "PLAN_ROUTE", PlanRoute(world), {"planned": "DOCK", "unreachable": "failed"}
        )
        smach.StateMachine.add(
            "DOCK", DriveRoute(world, docking=True), {"arrived": "docked", "halted": "failed"}
        )
    return sm


def plug_in_behaviour(world: RechargeWorld) -> smach.StateMachine:
    """FIND_SOCKET -> PLUG = Retry x3 [ALIGN_AND_INSERT -> CHECK_CURRENT]: plugged / failed."""
    attempt = smach.StateMachine(outcomes=["plugged", "missed"], input_keys=["robot"])
    with attempt:
        smach.StateMachine.add(
            "ALIGN_AND_INSERT",
            _robot_call(world.insert_plug, ok="inserted", failed="missed"),
            {"inserted": "CHECK_CURRENT"},
        )
        smach.StateMachine.add(
            "CHECK_CURRENT", _robot_call(world.charging_current, ok="plugged", failed="missed")
        )
    sm = smach.StateMachine(outcomes=["plugged", "failed", "preempted"], input_keys=["robot"])
    with sm:
        smach.StateMachine.add(
            "FIND_SOCKET",
            _robot_call(
                lambda robot: world.room_of(robot) in world.chargers, ok="found", failed="missing"
            ),
            {"found": "PLUG", "missing": "failed"},
        )
        smach.StateMachine.add(
            "PLUG",
            smach.Retry.wrap("ATTEMPT", attempt, attempts=PLUG_ATTEMPTS, retry_outcomes=["missed"]),
            {"missed": "failed"},
        )
    return sm


def charge_state(world: RechargeWorld) -> smach.State:
    return _robot_call(world.charge, ok="charged", failed="failed")


def unplug_state(world: RechargeWorld) -> smach.State:
    return _robot_call(world.pull_plug, ok="unplugged", failed="failed")


def place_state(world: RechargeWorld) -> smach.State:
    """Put the item in userdata ``item`` down in the robot's room: placed / failed."""
    return WorldCall(
        lambda ud: world.put_down(ud.robot, ud.item),
        ok="placed",
        failed="failed",
        input_keys=["robot", "item"],
        preemptable=False,
    )


def pick_behaviour(world: RechargeWorld) -> smach.StateMachine:
    """GRASP = Retry x2 [CLOSE_GRIPPER -> VERIFY_GRASP]: picked / failed."""
    keys = ["robot", "item", "room"]
    attempt = smach.StateMachine(outcomes=["held", "slipped"], input_keys=keys)
    with attempt:
        # The gripper closes either way; VERIFY_GRASP reads the finger gap to judge it.
        smach.StateMachine.add(
            "CLOSE_GRIPPER",
            WorldCall(
                lambda ud: world.grasp(ud.robot, ud.item, ud.room),
                ok="closed",
                failed="closed",
                input_keys=keys,
                preemptable=False,
            ),
            {"closed": "VERIFY_GRASP"},
        )
        smach.StateMachine.add(
            "VERIFY_GRASP",
            WorldCall(
                lambda ud: world.holds("holding", ud.robot, ud.item),
                ok="held",
                failed="slipped",
                input_keys=keys,
                preemptable=False,
            ),
        )
    sm = smach.StateMachine(outcomes=["picked", "failed", "preempted"], input_keys=keys)
    with sm:
        smach.StateMachine.add(
            "GRASP",
            smach.Retry.wrap(
                "ATTEMPT", attempt, attempts=GRASP_ATTEMPTS, retry_outcomes=["slipped"]
            ),
            {"held": "picked", "slipped": "failed"},
        )
    return sm


# -- skills: one machine per action, arguments preset in userdata ------------------------------


def _reported_skill(
    world: RechargeWorld,
    label: str,
    behaviour: smach.State,
    reports: dict[str, tuple[str, str]],
    bind: dict[str, object],
    remapping: dict[str, str] | None = None,
) -> smach.StateMachine:
    """LABEL, then per outcome of it a REPORT_X state (position, battery) ending the skill.

    ``reports``: outcome of ``behaviour`` -> (label of its report, outcome of the skill).
    """
    sm = skill_machine(bind=bind)
    with sm:
        smach.StateMachine.add(
            label,
            behaviour,
            {outcome: report for outcome, (report, _) in reports.items()},
            remapping=remapping,
        )
        for report, outcome in reports.values():
            smach.StateMachine.add(report, ObserveRobot(world, outcome))
    return sm


def move_skill(
    world: RechargeWorld, robot: str, origin: str, destination: str
) -> smach.StateMachine:
    """DRIVE_WITH_MONITOR -> REPORT (position, battery): succeeded / aborted."""
    return _reported_skill(
        world,
        "DRIVE_WITH_MONITOR",
        drive_with_monitor(world),
        {
            "arrived": ("REPORT_ARRIVAL", "succeeded"),
            "battery_low": ("REPORT_BATTERY_LOW", "aborted"),
            "failed": ("REPORT_FAILURE", "aborted"),
        },
        {"robot": robot, "corridor": [origin, destination]},
        remapping={"route": "corridor"},
    )


def go_to_charger_skill(world: RechargeWorld, robot: str, dock: str) -> smach.StateMachine:
    return _reported_skill(
        world,
        "GO_TO_DOCK",
        dock_behaviour(world),
        {"docked": ("REPORT_DOCKED", "succeeded"), "failed": ("REPORT_STRANDED", "aborted")},
        {"robot": robot, "destination": dock},
    )


def pick_skill(world: RechargeWorld, robot: str, item: str, room: str) -> smach.StateMachine:
    sm = skill_machine(bind={"robot": robot, "item": item, "room": room})
    with sm:
        smach.StateMachine.add(
            "PICK", pick_behaviour(world), {"picked": "succeeded", "failed": "REPORT_MISS"}
        )
        smach.StateMachine.add("REPORT_MISS", ObserveRobot(world, "aborted"))
    return sm


def place_skill(world: RechargeWorld, robot: str, item: str) -> smach.StateMachine:
    sm = skill_machine(bind={"robot": robot, "item": item})
    with sm:
        smach.StateMachine.add(
            "PLACE", place_state(world), {"placed": "succeeded", "failed": "aborted"}
        )
    return sm


def plug_in_skill(world: RechargeWorld, robot: str) -> smach.StateMachine:
    return _reported_skill(
        world,
        "PLUG_IN",
        plug_in_behaviour(world),
        {"plugged": ("REPORT_PLUGGED", "succeeded"), "failed": ("REPORT_UNPLUGGED", "aborted")},
        {"robot": robot},
    )


def charge_skill(world: RechargeWorld, robot: str) -> smach.StateMachine:
    return _reported_skill(
        world,
        "CHARGE",
        charge_state(world),
        {"charged": ("REPORT_CHARGED", "succeeded"), "failed": ("REPORT_NOT_CHARGED", "aborted")},
        {"robot": robot},
    )


def unplug_skill(world: RechargeWorld, robot: str) -> smach.StateMachine:
    sm = skill_machine(bind={"robot": robot})
    with sm:
        smach.StateMachine.add(
            "UNPLUG", unplug_state(world), {"unplugged": "succeeded", "failed": "aborted"}
        )
    return sm


def build_skills(world: RechargeWorld) -> SkillRegistry:
    """The registry binding every action of domain.pddl to its machine."""
    skills = SkillRegistry(simulated=True)
    skills.add("move", lambda r, a, b: move_skill(world, r, a, b))
    skills.add("go-to-charger", lambda r, a, dock: go_to_charger_skill(world, r, dock))
    skills.add("pick", lambda r, i, x: pick_skill(world, r, i, x))
    skills.add("place", lambda r, i, x: place_skill(world, r, i))
    skills.add("plug-in", lambda r, x: plug_in_skill(world, r))
    skills.add("charge", lambda r: charge_skill(world, r))
    skills.add("unplug", lambda r: unplug_skill(world, r))
    return skills


def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup:
    """The mission protocol of plan_bridge: skills acting on a fresh simulated world."""
    world = RechargeWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=build_skills(world), world=world)
