"""robosim_hospital written by hand: a dispatcher and one SMACH machine per robot.

The baseline of the study on order streams (docs/study.md, "Order streams"). Its
author writes no planner; the orders are dispatched as a floor manager would:

* **first come, first served, to the nearest idle robot.** The dispatcher (``DESK``)
  takes each order as it arrives and reads its goal: deliveries ``(At OBJECT SPAWN)``.
  An order it cannot read, or whose object or spawn no robot has a way to, is refused
  with the reason; one whose goal holds already is done. The waiting orders go out in
  the order they came (a higher priority first), each to the idle robot with the
  shortest way to its object; an order whose object another robot is carrying waits
  for it, and a robot whose hand is full only takes orders for what it holds;
* **a machine per order.** A robot that gets an order runs a machine written for it:
  for each delivery ``GO_TO_OBJECT -> OPEN -> PICK -> GO_TO_TARGET -> PLACE``
  (:func:`plan_bridge.robosim.scripting.deliver`: each drive leg and action tried three
  times, a door found closed opened, another way round a hallway found locked - the
  robots share what they found -, charging first when the battery is low);
* **an order given up goes back once.** When a robot gives up, the order goes back to
  the queue (another robot takes it, or the same one if it holds the object); after
  :data:`ORDER_ATTEMPTS` tries it fails, with where the last robot gave up.

The machines run in a :class:`~plan_bridge.robosim.scripting.TurnTakingConcurrence`, on
the world's simulated clock (a seeded run repeats exactly)::

    MISSION = DESK | NOVA | ORLA | PIM              (at once, taking turns on the clock)
    DESK    = TAKE_ORDERS -> ASSIGN -> WAIT_FOR_NEWS --news--> TAKE_ORDERS
                                                     --finished--> succeeded
    ROBOT   = WAIT_FOR_ORDER --order--> SERVE --served--> WAIT_FOR_ORDER
                             --closed--> succeeded
    SERVE   runs DELIVER_<OBJECT> -> ... (one deliver machine per delivery of the order)

The orders: ``scripted(task, *, seed, fail_rate, variant="", orders=FILE)`` draws the
orders file's orders from the run's seed, as ``plan-bridge run --orders FILE`` does
(the same orders at the same times); without ``orders`` the task's goal is the one
order, at time 0. The mission's ``extra["orders"]`` is its
:class:`~plan_bridge.robosim.scripting.OrderLedger`: the book of orders and
``figures()`` (counts by status, latency p50/p95, orders done per hour, each robot's
busy share), as a planned order mission's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import smach
from plan_bridge.errors import PlanBridgeError
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import scripted_world
from plan_bridge.orders.book import OrderBook
from plan_bridge.orders.order import Order, OrderStatus
from plan_bridge.orders.order_file import load_orders
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact
from plan_bridge.robosim.scripting import (
    ClockSignal,
    Delivery,
    OrderLedger,
    TurnTakingConcurrence,
    charger_spot,
    deliver,
    deliveries_of,
    locked_halls,
    read_order_goal,
    route,
    route_length,
    whereabouts,
)
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["ORDER_ATTEMPTS", "Desk", "scripted"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]
#: Robots that try one order before it fails (the first and one more).
ORDER_ATTEMPTS = 2
_INF = float("inf")


class Desk:
    """What the dispatcher and the robots' machines share: the ledger of orders, each
    accepted order's deliveries, each robot's order, the hallways known blocked, news."""

    def __init__(self, world: RobosimWorld, ledger: OrderLedger, goals: dict[str, list[Fact]]):
        self.world = world
        self.ledger = ledger
        self.book = ledger.orders
        self.goals = goals
        """Goals read already (the task's goal when there is no orders file)."""
        self.signal = ClockSignal(world)
        self.work: dict[str, list[Delivery]] = {}
        self.atoms: dict[str, list[Fact]] = {}
        self.jobs: dict[str, str | None] = dict.fromkeys(ledger.robots)
        self.blocked: set[str] = set(locked_halls(world))
        self.closed = False
        """Every order is accounted for: the robots stop."""

    def read(self, text: str) -> list[Fact]:
        if text in self.goals:
            return self.goals[text]
        return read_order_goal(self.world, FOLDER, text)

    def holds(self, order_id: str) -> bool:
        return all(self.world.truth(atom) for atom in self.atoms[order_id])

    def metres(self, start: str | None, goal: str | None) -> float:
        if start is None or goal is None:
            return _INF
        return route_length(self.world, route(self.world, start, goal, self.blocked))

    def here(self, robot: str) -> str:
        return self.world.spot_of(self.world.robot(robot))


class _DeskState(smach.State):
    """A state of the dispatcher; a preempt wakes it."""

    def __init__(self, desk: Desk, outcomes: list[str]) -> None:
        super().__init__(outcomes=outcomes)
        self.desk = desk

    def request_preempt(self) -> None:
        super().request_preempt()
        self.desk.signal.notify()


class TakeOrders(_DeskState):
    """Take the orders that have arrived: read each goal (refused when it cannot be
    read or is not deliveries), done at once when it holds; queued otherwise."""

    def __init__(self, desk: Desk) -> None:
        super().__init__(desk, ["taken"])

    def execute(self, ud: smach.UserData) -> str:
        desk, book = self.desk, self.desk.book
        now = desk.ledger.now()
        for order in book.arrivals(now):
            try:
                atoms = desk.read(order.goal)
                deliveries = deliveries_of(desk.world, atoms)
            except (PlanBridgeError, ValueError) as exc:
                book.refuse(order.id, str(exc), now)
                continue
            book.accept(order.id, atoms, now)
            desk.atoms[order.id], desk.work[order.id] = list(atoms), deliveries
        for state in book.open_orders():
            if state.status is OrderStatus.QUEUED and desk.holds(state.id):
                book.done(state.id, now)
        return "taken"


class Assign(_DeskState):
    """Give the waiting orders, first come first served (a higher priority first), to
    the nearest idle robots; refuse (or fail, if it had started) an order no robot has a
    way to."""

    def __init__(self, desk: Desk) -> None:
        super().__init__(desk, ["assigned"])

    def execute(self, ud: smach.UserData) -> str:
        desk = self.desk
        waiting = [s for s in desk.book.open_orders() if s.status is OrderStatus.QUEUED]
        for state in sorted(waiting, key=lambda s: (-s.order.priority, s.arrived or 0.0)):
            robot = self._robot_for(state.id)
            if robot is not None:
                desk.jobs[robot] = state.id
                desk.book.assign(state.id, [robot], desk.ledger.now())
        desk.signal.notify()
        return "assigned"

    def _robot_for(self, order_id: str) -> str | None:
        """The robot to take the order now (None: it waits, or it was given up)."""
        desk = self.desk
        first = desk.work[order_id][0]
        place, holder = whereabouts(desk.world, first.item)
        carried = {d.item for o in desk.jobs.values() if o is not None for d in desk.work[o]}
        if first.item in carried:
            return None  # another robot carries it: the order waits
        free = [r for r in desk.jobs if desk.world.robot(r).manipulated_object is None]
        start = place if holder is None else desk.here(holder)
        reach = {r: desk.metres(desk.here(r), place) for r in free}
        if start is None:
            why = f"{first.item} is nowhere to be found"
        elif desk.metres(start, first.target) == _INF:
            known = ", ".join(sorted(desk.blocked)) or "none"
            why = f"no way from {start} to {first.target} (hallways known blocked: {known})"
        elif holder is not None:
            return holder if desk.jobs[holder] is None else None
        elif not free:
            why = "every robot's hand is full"
        elif min(reach.values()) == _INF:
            why = f"no robot has a way to {first.item}"
        else:
            idle = [r for r in free if desk.jobs[r] is None and reach[r] < _INF]
            return min(idle, key=lambda r: (reach[r], r)) if idle else None
        self._give_up(order_id, f"no robot can do it: {why}")
        return None

    def _give_up(self, order_id: str, reason: str) -> None:
        book, now = self.desk.book, self.desk.ledger.now()
        if book.get(order_id).started is None:
            book.refuse(order_id, reason, now)
        else:
            book.fail(order_id, reason, now)


class WaitForNews(_DeskState):
    """Wait until the next order arrives or a robot reports; ``finished`` when every
    order is accounted for and no robot works."""

    def __init__(self, desk: Desk) -> None:
        super().__init__(desk, ["news", "finished", "preempted"])

    def execute(self, ud: smach.UserData) -> str:
        desk = self.desk
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        busy = any(order is not None for order in desk.jobs.values())
        if desk.book.finished() and not busy:
            desk.closed = True
            desk.ledger.close()
            desk.signal.notify()
            return "finished"
        arrival = desk.book.next_arrival()
        desk.signal.wait(None if arrival is None else desk.ledger.t0 + max(0.0, arrival))
        return "news"


class WaitForOrder(smach.State):
    """A robot waits for the dispatcher to give it an order (``order``), or for the end
    of the day (``closed``)."""

    def __init__(self, desk: Desk, robot: str) -> None:
        super().__init__(outcomes=["order", "closed", "preempted"])
        self.desk, self.robot = desk, robot

    def execute(self, ud: smach.UserData) -> str:
        while True:
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            if self.desk.jobs[self.robot] is not None:
                return "order"
            if self.desk.closed:
                return "closed"
            self.desk.signal.wait()

    def request_preempt(self) -> None:
        super().request_preempt()
        self.desk.signal.notify()


class Serve(smach.State):
    """Serve the robot's order with a machine written for it (a deliver machine per
    delivery), then report to the dispatcher: done, or given up (back to the queue
    until :data:`ORDER_ATTEMPTS` tries, then failed)."""

    def __init__(self, desk: Desk, robot: str, charger: str | None) -> None:
        super().__init__(outcomes=["served", "preempted"])
        self.desk, self.robot, self.charger = desk, robot, charger
        self._running: smach.State | None = None

    def order_machine(self, order_id: str) -> smach.StateMachine:
        """``DELIVER_<OBJECT> -> ...``: the order's deliveries in turn; outcomes ``done``,
        ``aborted``, ``preempted``."""
        desk, world = self.desk, self.desk.world
        keys = ["blocked", "legs"]
        sm = smach.StateMachine(
            outcomes=["done", "aborted", "preempted"], input_keys=keys, output_keys=keys
        )
        stages = []
        for delivery in desk.work[order_id]:
            place, holder = whereabouts(world, delivery.item)
            holding = holder == self.robot
            if place == delivery.target and not holding:
                continue  # there already
            machine = deliver(
                world, self.robot, delivery.item, delivery.target, self.charger,
                source=place, holding=holding,
            )  # fmt: skip
            stages.append((f"DELIVER_{delivery.item.upper()}", machine))
        with sm:
            if not stages:
                smach.StateMachine.add(
                    "NOTHING_TO_DO", smach.CBState(lambda ud: "done", outcomes=["done"])
                )
            for n, (label, machine) in enumerate(stages):
                following = stages[n + 1][0] if n + 1 < len(stages) else "done"
                smach.StateMachine.add(label, machine, {"done": following})
        return sm

    def execute(self, ud: smach.UserData) -> str:
        desk, book = self.desk, self.desk.book
        order_id = desk.jobs[self.robot]
        assert order_id is not None
        began = desk.ledger.now()
        book.activate(order_id, began)
        machine = self.order_machine(order_id)
        gave_up: list[str] = []

        def note(event: Any) -> None:  # where the robot gave up: the innermost state first
            if event.kind == "state_exited" and event.outcome in ("failed", "no_way"):
                gave_up.append(f"{event.path} ({event.outcome})")

        machine.add_listener(note)
        inner = smach.UserData()
        inner.blocked, inner.legs = sorted(desk.blocked), []
        self._running = machine
        try:
            outcome = machine.execute(inner)
        finally:
            self._running = None
        desk.blocked |= set(inner.blocked)
        now = desk.ledger.now()
        desk.ledger.worked(self.robot, now - began)
        desk.jobs[self.robot] = None
        state = book.get(order_id)
        if not state.final:
            if outcome == "done" and desk.holds(order_id):
                book.done(order_id, now)
            elif outcome != "preempted":
                reason = f"{self.robot} gave up at {gave_up[0] if gave_up else 'its order'}"
                if book.note_attempt(order_id) >= ORDER_ATTEMPTS:
                    book.fail(order_id, reason, now)
                else:
                    book.requeue(order_id, now, reason)
        desk.signal.notify()
        if outcome == "preempted":
            self.service_preempt()
            return "preempted"
        return "served"

    def request_preempt(self) -> None:
        super().request_preempt()
        running = self._running
        if running is not None:
            running.request_preempt()


def _desk_machine(desk: Desk) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=OUTCOMES)
    with sm:
        smach.StateMachine.add("TAKE_ORDERS", TakeOrders(desk), {"taken": "ASSIGN"})
        smach.StateMachine.add("ASSIGN", Assign(desk), {"assigned": "WAIT_FOR_NEWS"})
        smach.StateMachine.add(
            "WAIT_FOR_NEWS",
            WaitForNews(desk),
            {"news": "TAKE_ORDERS", "finished": "succeeded"},
        )
    return sm


def _robot_machine(desk: Desk, robot: str, charger: str | None) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=OUTCOMES)
    with sm:
        smach.StateMachine.add(
            "WAIT_FOR_ORDER", WaitForOrder(desk, robot), {"order": "SERVE", "closed": "succeeded"}
        )
        smach.StateMachine.add("SERVE", Serve(desk, robot, charger), {"served": "WAIT_FOR_ORDER"})
    return sm


def scripted(
    task: PlanningTask,
    *,
    seed: int,
    fail_rate: float,
    variant: str = "",
    orders: str | Path | None = None,
) -> ScriptedMission:
    """The dispatcher and the robots' machines, acting on a fresh world: the orders of
    the orders file ``orders`` (drawn from ``seed``), or the task's goal as one order."""
    world = scripted_world(FOLDER, task, seed=seed, fail_rate=fail_rate, variant=variant)
    goals: dict[str, list[Fact]] = {}
    if orders is not None:
        scheduled = load_orders(orders).draw(seed)
    else:
        text = " ".join(format_fact(atom) for atom in task.goal_facts)
        goals[text] = list(task.goal_facts)
        scheduled = [Order("goal", text, 0.0, origin="the task's goal")]
    robots = [r.name for r in world.model.robots]
    ledger = OrderLedger(world, OrderBook(scheduled, closed=True), robots)
    desk = Desk(world, ledger, goals)
    charger = charger_spot(world)
    mission = TurnTakingConcurrence(
        world,
        outcomes=OUTCOMES,
        default_outcome="aborted",
        outcome_map={"succeeded": {"DESK": "succeeded"}},
    )
    mission.add("DESK", _desk_machine(desk))
    for robot in robots:
        mission.add(robot.upper(), _robot_machine(desk, robot, charger))
    return ScriptedMission(mission, world, extra={"orders": ledger})
