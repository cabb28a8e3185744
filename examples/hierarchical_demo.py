"""A hierarchical, concurrent SMACH machine: a robot patrols while a monitor watches its battery.

Run: ``./dev run`` (or ``python examples/hierarchical_demo.py --seed 3``).

Structure::

    ROOT (StateMachine)
      PATROL (Concurrence)              <- ends when either child ends
        TOUR (Iterator over waypoints)
          VISIT (StateMachine: GO -> SCAN, GO wrapped in a Retry)
        BATTERY (monitor: preempts TOUR when the battery is low)
      RECHARGE (Timeout around DOCK)    <- only when the battery ran low
      REPORT

Every transition is printed by an event listener, and the run ends with a summary.
"""

from __future__ import annotations

import argparse
import random
import sys
from typing import Any

import smach
from smach.introspection.events import Event, PreemptRequested, Transition


class Robot:
    """The little simulated world the states act on."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.battery = 100.0
        self.position = "dock"


class Go(smach.State):
    """Drive to ``waypoint``; the corridor is sometimes blocked."""

    def __init__(self, robot: Robot) -> None:
        super().__init__(outcomes=["arrived", "blocked", "preempted"], input_keys=["waypoint"])
        self.robot = robot

    def execute(self, ud: smach.UserData) -> str:
        if self.sleep(0.01):  # driving takes time; a preempt stops it at once
            self.service_preempt()
            return "preempted"
        if self.robot.rng.random() < 0.3:
            return "blocked"
        self.robot.position = ud.waypoint
        self.robot.battery -= 9.0
        return "arrived"


class Scan(smach.State):
    """Look around at the current waypoint and log what was seen."""

    def __init__(self, robot: Robot) -> None:
        super().__init__(outcomes=["done"], input_keys=["waypoint"], io_keys=["seen"])
        self.robot = robot

    def execute(self, ud: smach.UserData) -> str:
        ud.seen = [*ud.seen, ud.waypoint]
        self.robot.battery -= 3.0
        return "done"


class BatteryMonitor(smach.State):
    """Polls the battery; returns 'low' below the threshold."""

    def __init__(self, robot: Robot, threshold: float) -> None:
        super().__init__(outcomes=["low", "preempted"])
        self.robot, self.threshold = robot, threshold

    def execute(self, ud: smach.UserData) -> str:
        while not self.sleep(0.005):
            if self.robot.battery < self.threshold:
                return "low"
        self.service_preempt()
        return "preempted"


def build(robot: Robot, waypoints: list[str]) -> smach.StateMachine:
    mission = smach.UserData({"seen": []})
    visit = smach.StateMachine(
        outcomes=["visited", "failed", "preempted"],
        input_keys=["waypoint", "seen"],
        output_keys=["seen"],
    )
    with visit:
        smach.StateMachine.add(
            "GO",
            smach.Retry.wrap("DRIVE", Go(robot), attempts=3, retry_outcomes=["blocked"]),
            transitions={"arrived": "SCAN", "blocked": "failed"},
        )
        smach.StateMachine.add("SCAN", Scan(robot), transitions={"done": "visited"})

    tour = smach.Iterator(
        outcomes=["toured", "failed", "preempted"],
        input_keys=["seen"],
        output_keys=["seen"],
        # After a recharge the tour resumes with the waypoints not scanned yet.
        it=lambda: [w for w in waypoints if w not in mission.seen],
        it_label="waypoint",
        exhausted_outcome="toured",
    )
    with tour:
        smach.Iterator.set_contained_state(
            "VISIT", visit, loop_outcomes=["visited"], final_outcome_map={}
        )

    patrol = smach.Concurrence(
        outcomes=["patrolled", "low_battery", "failed"],
        default_outcome="failed",
        input_keys=["seen"],
        output_keys=["seen"],
        outcome_map={"patrolled": {"TOUR": "toured"}, "low_battery": {"BATTERY": "low"}},
        child_termination_cb=lambda outcomes: True,  # the first child to finish stops the other
    )
    with patrol:
        smach.Concurrence.add("TOUR", tour)
        smach.Concurrence.add("BATTERY", BatteryMonitor(robot, threshold=45.0))

    def dock(ud: Any) -> str:
        robot.battery = 100.0
        robot.position = "dock"
        return "charged"

    root = smach.StateMachine(outcomes=["mission_complete", "mission_failed"])
    root.userdata = mission
    with root:
        smach.StateMachine.add(
            "PATROL",
            patrol,
            transitions={
                "patrolled": "REPORT",
                "low_battery": "RECHARGE",
                "failed": "mission_failed",
            },
        )
        smach.StateMachine.add(
            "RECHARGE",
            smach.Timeout.wrap("DOCK", smach.CBState(dock, outcomes=["charged"]), timeout=2.0),
            transitions={
                "charged": "PATROL",
                "timeout": "mission_failed",
                "preempted": "mission_failed",
            },
        )
        smach.StateMachine.add(
            "REPORT",
            smach.CBState(lambda ud: "done", outcomes=["done"], input_keys=["seen"]),
            transitions={"done": "mission_complete"},
        )
    return root


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1, help="seed of the simulated faults")
    args = parser.parse_args(argv)
    robot = Robot(args.seed)
    root = build(robot, ["hall", "lab", "office", "kitchen", "lobby", "garage", "roof"])
    transitions = 0

    def show(event: Event) -> None:
        nonlocal transitions
        if isinstance(event, Transition):
            transitions += 1
            print(f"  {event.path:<28} {event.source} --{event.outcome}--> {event.target}")
        elif isinstance(event, PreemptRequested) and event.path.endswith("TOUR"):
            print(f"  {event.path:<28} preempt requested (battery {robot.battery:.0f}%)")

    root.add_listener(show)
    report = smach.validate(root)
    print(f"validated {sum(1 for _ in smach.snapshot(root).walk())} states: {report}")
    outcome = root.execute()
    print(
        f"outcome: {outcome}; waypoints scanned: {root.userdata.seen}; "
        f"{transitions} transitions; battery {robot.battery:.0f}%"
    )
    return 0 if outcome == "mission_complete" else 1


if __name__ == "__main__":
    sys.exit(main())
