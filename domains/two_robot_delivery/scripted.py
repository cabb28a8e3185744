"""The two-robot delivery written by hand as one SMACH machine: no planner.

A Concurrence runs one machine per robot. Each robot works through its list of
deliveries (item, destination): follow the fixed route to its storeroom, pick,
follow the fixed route to the destination, drop. Routes are the shortest ones on
the author's map, computed once. The recovery the author anticipated:

- a person in the way: the move machine retries the drive; the script tries a
  failed leg once more,
- an item slipping back onto the shelf or a gripper that stays shut: the pick and
  drop machines retry; the script tries a failed pick or drop once more.

Not anticipated, so the run fails: a blocked door on the fixed route, an item that
falls off on the way.
"""

from __future__ import annotations

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import fewest_hops

from .skills import drop_machine, move_machine, pick_machine
from .world import DeliveryWorld

__all__ = ["scripted"]

#: How often the script tries a failed leg, pick or drop again.
SECOND_TRIES = 1


def shortest_route(doors: set[tuple[str, str]], start: str, goal: str) -> list[tuple[str, str]]:
    """The legs of the shortest route over ``doors`` (the author's map)."""
    legs = fewest_hops(start, goal, lambda here: [(b, None) for a, b in sorted(doors) if a == here])
    if legs is None:
        raise ValueError(f"the map has no route from {start} to {goal}")
    return [(a, b) for a, b, _ in legs]


class PlanRoute(smach.State):
    """Look up the fixed route from where the robot is to ``goal``."""

    def __init__(self, world: DeliveryWorld, doors: set[tuple[str, str]]) -> None:
        super().__init__(
            outcomes=["ready", "lost"], input_keys=["robot", "goal"], output_keys=["legs", "tries"]
        )
        self.world = world
        self.doors = doors

    def execute(self, ud: smach.UserData) -> str:
        here = self.world.location(ud.robot)
        if here is None:
            return "lost"
        ud.legs = shortest_route(self.doors, here, ud.goal)
        ud.tries = 0
        return "ready"


@smach.cb_interface(
    outcomes=["leg", "arrived"], input_keys=["legs"], output_keys=["legs", "source", "target"]
)
def next_leg(ud: smach.UserData) -> str:
    legs = list(ud.legs)
    if not legs:
        return "arrived"
    ud.source, ud.target = legs[0]
    ud.legs = legs[1:]
    return "leg"


@smach.cb_interface(outcomes=["again", "give_up"], input_keys=["tries"], output_keys=["tries"])
def try_again(ud: smach.UserData) -> str:
    """The author's recovery: one more try, then give up."""
    if ud.tries >= SECOND_TRIES:
        return "give_up"
    ud.tries = ud.tries + 1
    return "again"


def route_machine(world: DeliveryWorld, doors: set[tuple[str, str]]) -> smach.StateMachine:
    """PLAN_ROUTE -> (NEXT_LEG -> MOVE)*, one more try per failed leg; keys robot, goal."""
    sm = smach.StateMachine(
        outcomes=["arrived", "failed", "preempted"], input_keys=["robot", "goal"]
    )
    with sm:
        smach.StateMachine.add(
            "PLAN_ROUTE",
            PlanRoute(world, doors),
            transitions={"ready": "NEXT_LEG", "lost": "failed"},
        )
        smach.StateMachine.add(
            "NEXT_LEG", smach.CBState(next_leg), transitions={"leg": "MOVE", "arrived": "arrived"}
        )
        smach.StateMachine.add(
            "MOVE",
            move_machine(world),
            transitions={"succeeded": "NEXT_LEG", "aborted": "LEG_AGAIN"},
        )
        smach.StateMachine.add(
            "LEG_AGAIN",
            smach.CBState(try_again),
            transitions={"again": "MOVE", "give_up": "failed"},
        )
    return sm


def robot_machine(
    world: DeliveryWorld,
    doors: set[tuple[str, str]],
    robot: str,
    store: str,
    jobs: list[tuple[str, str]],
) -> smach.Iterator:
    """One robot's deliveries, one after the other: (item, destination) per job."""
    deliver = smach.StateMachine(
        outcomes=["delivered", "failed", "preempted"], input_keys=["job", "robot"]
    )
    deliver.userdata.store = store
    with deliver:

        @smach.cb_interface(
            outcomes=["go"], input_keys=["job"], output_keys=["item", "destination", "tries"]
        )
        def take_job(ud: smach.UserData) -> str:
            item, destination = ud.job
            ud.item, ud.destination, ud.tries = item, destination, 0
            return "go"

        smach.StateMachine.add(
            "TAKE_JOB", smach.CBState(take_job), transitions={"go": "GO_TO_STORE"}
        )
        # Go to the store and PICK, then to the destination and DROP (each one more try).
        for key, act, machine, then in (
            ("store", "PICK", pick_machine, "GO_TO_DESTINATION"),
            ("destination", "DROP", drop_machine, "delivered"),
        ):
            smach.StateMachine.add(
                f"GO_TO_{key.upper()}",
                route_machine(world, doors),
                transitions={"arrived": act, "failed": "failed"},
                remapping={"goal": key},
            )
            smach.StateMachine.add(
                act,
                machine(world),
                transitions={"succeeded": then, "aborted": f"{act}_AGAIN"},
                remapping={"room": key},
            )
            smach.StateMachine.add(
                f"{act}_AGAIN",
                smach.CBState(try_again),
                transitions={"again": act, "give_up": "failed"},
            )
    jobs_loop = smach.Iterator(
        outcomes=["done", "failed", "preempted"],
        input_keys=[],
        output_keys=[],
        it=jobs,
        it_label="job",
        exhausted_outcome="done",
    )
    jobs_loop.userdata.robot = robot
    with jobs_loop:
        smach.Iterator.set_contained_state("DELIVER", deliver, loop_outcomes=["delivered"])
    return jobs_loop


def _both_done(outcomes: dict[str, str | None]) -> str:
    values = set(outcomes.values())
    if values == {"done"}:
        return "done"
    if "failed" in values:
        return "failed"
    return "preempted" if "preempted" in values else "failed"


def scripted(task: PlanningTask, *, seed: int, fail_rate: float) -> ScriptedMission:
    """The hand-written baseline in the same simulated world as the planned runs."""
    world = DeliveryWorld(task, seed=seed, fail_rate=fail_rate)
    facts = task.initial_facts
    doors = {(f[1], f[2]) for f in facts if f[0] == "connected"}
    destinations = {g[1]: g[2] for g in task.goal_facts if g[0] == "item-at"}
    both = smach.Concurrence(
        outcomes=["done", "failed", "preempted"], default_outcome="failed", outcome_cb=_both_done
    )
    with both:
        for robot in world.robots:
            items = sorted(f[2] for f in facts if f[0] == "suits" and f[1] == robot)
            store = next(f[2] for f in sorted(facts) if f[0] == "item-at" and f[1] in items)
            jobs = [(item, destinations[item]) for item in items if item in destinations]
            smach.Concurrence.add(robot.upper(), robot_machine(world, doors, robot, store, jobs))
    sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    with sm:
        smach.StateMachine.add("BOTH_ROBOTS", both)
    return ScriptedMission(machine=sm, world=world)
