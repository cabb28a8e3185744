"""The table-clearing mission written by hand as one SMACH machine: no planner.

This is how the PR2 demo was scripted: the author knows the map and the list of
objects, walks to each object, picks it, brings it to the cart, and finally pushes
the cart to the kitchen along a fixed route. The recovery the author anticipated
is written out explicitly:

- an object not seen at first: the pick skill re-detects (and the script tries the
  pick once more),
- an object lying elsewhere on the table: the script walks to the side of the table
  that reaches it and picks it there,
- an object slipping back onto the table, a gripper that does not open, a jammed
  caster: handled inside the pick, place and push machines (retries, backing up).

What the author did not anticipate makes the script fail: an object that falls to
the floor, a corridor blocked on the fixed route to the kitchen.
"""

from __future__ import annotations

import itertools

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.skills.kit import fewest_hops

from .skills import pick_machine, place_machine, push_machine
from .world import TableWorld

__all__ = ["scripted"]

OUTCOMES = ["done", "failed", "preempted"]


def _route(edges: set[tuple[str, str]], start: str, goal: str) -> list[str]:
    """The shortest route over ``edges`` (the author's map), start and goal included."""
    legs = fewest_hops(start, goal, lambda here: [(b, None) for a, b in sorted(edges) if a == here])
    if legs is None:
        raise ValueError(f"the map has no route from {start} to {goal}")
    return [start, *(to for _, to, _ in legs)]


class WalkTo(smach.State):
    """Walk through the dining room to ``goal`` along the author's map."""

    def __init__(self, world: TableWorld, edges: set[tuple[str, str]]) -> None:
        super().__init__(outcomes=["arrived", "failed", "preempted"], input_keys=["robot", "goal"])
        self.world = world
        self.edges = edges

    def execute(self, ud: smach.UserData) -> str:
        here = self.world.robot_location(ud.robot)
        if here is None:
            return "failed"
        route = _route(self.edges, here, ud.goal)
        for source, target in itertools.pairwise(route):
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            if not self.world.walk(ud.robot, source, target):
                return "failed"
        return "arrived"


class RecoverPick(smach.State):
    """The author's recovery after a failed pick: look at what the pick saw."""

    def __init__(self, sides: dict[str, str], floors: set[str]) -> None:
        super().__init__(
            outcomes=["retarget", "retry", "give_up"],
            input_keys=["item", "spot", "observations", "pick_tries"],
            output_keys=["spot", "side", "pick_tries"],
        )
        self.sides = sides
        self.floors = floors

    def execute(self, ud: smach.UserData) -> str:
        tries = ud.pick_tries + 1
        ud.pick_tries = tries
        if tries > 2:
            return "give_up"
        seen: dict[Fact, bool] = ud.observations
        for fact, truth in seen.items():
            if truth and fact[0] == "item-at" and fact[1] == ud.item and fact[2] != ud.spot:
                if fact[2] in self.floors:
                    return "give_up"  # not anticipated: the floor is out of the script's reach
                ud.spot = fact[2]
                ud.side = self.sides[fact[2]]
                return "retarget"
        return "retry"


def scripted(task: PlanningTask, *, seed: int, fail_rate: float) -> ScriptedMission:
    """The hand-written baseline in the same simulated world as the planned runs."""
    world = TableWorld(task, seed=seed, fail_rate=fail_rate)
    facts = task.initial_facts
    robot = task.objects_of_type("robot")[0]
    cart = task.objects_of_type("cart")[0]
    walkable = {(f[1], f[2]) for f in facts if f[0] == "adjacent"}
    passages = {(f[1], f[2]) for f in facts if f[0] == "passage"}
    floors = {s for s in task.objects_of_type("spot") if s.startswith("floor")}
    # The side of the table the author walks to for each spot (the first that reaches it).
    sides: dict[str, str] = {}
    for fact in sorted(facts):
        if fact[0] == "reaches":
            sides.setdefault(fact[2], fact[1])
    cart_spot = next(f[2] for f in facts if f[0] == "cart-at" and f[1] == cart)
    kitchen = next(g[2] for g in task.goal_facts if g[0] == "cart-at")
    items = sorted((f[1], f[2]) for f in facts if f[0] == "item-at")

    sm = smach.StateMachine(outcomes=OUTCOMES)
    sm.userdata.robot = robot
    sm.userdata.cart = cart
    sm.userdata.cart_spot = cart_spot
    route = _route(passages, cart_spot, kitchen)  # the fixed route to the kitchen
    legs = list(itertools.pairwise(route))

    def add_walk(label: str, goal: str, arrived: str) -> None:
        """Walk to the place in userdata ``goal`` along the author's map."""
        smach.StateMachine.add(
            label,
            WalkTo(world, walkable),
            transitions={"arrived": arrived, "failed": "failed"},
            remapping={"goal": goal},
        )

    clear_one = smach.StateMachine(
        outcomes=["cleared", "failed", "preempted"],
        input_keys=["entry", "robot", "cart", "cart_spot"],
    )
    with clear_one:

        @smach.cb_interface(
            outcomes=["chosen"],
            input_keys=["entry"],
            output_keys=["item", "spot", "side", "pick_tries"],
        )
        def choose(ud: smach.UserData) -> str:
            item, spot = ud.entry
            ud.item, ud.spot, ud.side = item, spot, sides[spot]
            ud.pick_tries = 0
            return "chosen"

        smach.StateMachine.add(
            "CHOOSE", smach.CBState(choose), transitions={"chosen": "GO_TO_OBJECT"}
        )
        add_walk("GO_TO_OBJECT", "side", "PICK")
        smach.StateMachine.add(
            "PICK",
            pick_machine(world),
            transitions={"succeeded": "GO_TO_CART", "aborted": "RECOVER_PICK"},
        )
        smach.StateMachine.add(
            "RECOVER_PICK",
            RecoverPick(sides, floors),
            transitions={"retarget": "GO_TO_OBJECT", "retry": "PICK", "give_up": "failed"},
        )
        add_walk("GO_TO_CART", "cart_spot", "PLACE")
        smach.StateMachine.add(
            "PLACE", place_machine(world), transitions={"succeeded": "cleared", "aborted": "failed"}
        )

    clear_all = smach.Iterator(
        outcomes=["cleared", "failed", "preempted"],
        input_keys=["robot", "cart", "cart_spot"],
        output_keys=[],
        it=items,
        it_label="entry",
        exhausted_outcome="cleared",
    )
    with clear_all:
        smach.Iterator.set_contained_state("CLEAR_ONE", clear_one, loop_outcomes=["cleared"])

    push_all = smach.Iterator(
        outcomes=["arrived", "failed", "preempted"],
        input_keys=["robot", "cart"],
        output_keys=[],
        it=legs,
        it_label="leg",
        exhausted_outcome="arrived",
    )
    push_leg = smach.StateMachine(
        outcomes=["pushed", "failed", "preempted"], input_keys=["leg", "robot", "cart"]
    )
    with push_leg:

        @smach.cb_interface(
            outcomes=["ready"], input_keys=["leg"], output_keys=["source", "target"]
        )
        def unpack(ud: smach.UserData) -> str:
            ud.source, ud.target = ud.leg
            return "ready"

        smach.StateMachine.add("LEG", smach.CBState(unpack), transitions={"ready": "PUSH_CART"})
        smach.StateMachine.add(
            "PUSH_CART",
            push_machine(world),
            transitions={"succeeded": "pushed", "aborted": "failed"},
        )
    with push_all:
        smach.Iterator.set_contained_state("PUSH_LEG", push_leg, loop_outcomes=["pushed"])

    with sm:
        smach.StateMachine.add(
            "CLEAR_TABLE", clear_all, transitions={"cleared": "GO_TO_CART", "failed": "failed"}
        )
        add_walk("GO_TO_CART", "cart_spot", "PUSH_TO_KITCHEN")
        smach.StateMachine.add(
            "PUSH_TO_KITCHEN", push_all, transitions={"arrived": "done", "failed": "failed"}
        )
    return ScriptedMission(machine=sm, world=world)
