"""The executive of a day of orders: plan for the orders that have arrived, run, repeat.

An :class:`OrderExecutive` is an :class:`~plan_bridge.execution.executive.Executive`
whose goal is not fixed: it is the conjunction of the open orders' goals (at most
``per_robot`` orders a robot at a time, highest priority first: the *horizon*), and
the mission goes on while orders may still come. Its loop:

1. take the orders that have arrived (:class:`~plan_bridge.orders.book.OrderBook`):
   each is accepted (its goal read by ``goal_of``, in the target's words) or refused
   with the reason; mark done the orders whose goal holds;
2. with no open order, wait for the next arrival (a simulated clock jumps to it), or
   end when the book is finished (closed, nothing left to arrive, every order final);
3. plan for the horizon; when no plan reaches it, plan each order alone: one that has
   no plan alone is refused (never started) or failed, with the planner's reason;
   orders that only conflict with each other are planned a few at a time;
4. run the plan; the orders it serves become ``assigned`` to the robots whose steps
   achieve them (:mod:`~plan_bridge.orders.assignment`) and ``active`` when one of
   their steps starts. An order arriving (or cancelled) while the plan runs *holds* the
   plan (:class:`~plan_bridge.execution.steps.PlanHold`): no new step starts, the
   running ones finish, and the loop plans again with it. No running step is stopped
   for an order;
5. after a failure, recover as the executive does (retry, repair, replan) within the
   policy's budgets, counted afresh whenever the orders change. When recovery gives up,
   only the orders of the failed step's robots are given up on: each goes back to the
   queue (another robot may take it over) until ``attempts`` plans failed for it,
   then it fails with the reason. The other orders go on.

Every status change is an :class:`~plan_bridge.orders.order.OrderChanged` event
(journal, viewer). The report's ``orders`` hold the book's summary.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Any

from plan_bridge.belief import FactSnapshot, values_of
from plan_bridge.errors import PlanBridgeError
from plan_bridge.execution.clock import clock_of
from plan_bridge.execution.control import task_with_goal
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.repair import Recovery
from plan_bridge.execution.replanner import MissionEnded
from plan_bridge.execution.steps import StepRecord
from plan_bridge.orders.assignment import agents_of, order_work
from plan_bridge.orders.book import OrderBook, OrderBookError
from plan_bridge.orders.order import OrderChanged, OrderState, OrderStatus
from plan_bridge.orders.requests import OrderDesk
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact
from plan_bridge.planning.types import PlanStep

__all__ = [
    "BENCH_S",
    "DEFAULT_ATTEMPTS",
    "DEFAULT_PER_ROBOT",
    "GoalReader",
    "OrderExecutive",
    "UpkeepGoals",
]

#: Orders planned at once per robot (the horizon): enough to chain a robot's work,
#: few enough that a plan stays a task's size however long the queue.
DEFAULT_PER_ROBOT = 2
#: Plans given up for one order (its robots' recovery exhausted) before it fails.
DEFAULT_ATTEMPTS = 2
#: Seconds (mission clock) a robot whose step failed past recovery is left out of
#: plans, so that another robot takes its orders over.
BENCH_S = 300.0

UpkeepGoals = Callable[[Collection[Fact], Mapping[Fact, float]], Sequence[Fact]]
"""Goal atoms for the robots' own sake in a belief (facts, values): a charge for a robot
low on battery (:meth:`~plan_bridge.missions.mission.Target.upkeep_goals`)."""

GoalReader = Callable[[str], Sequence[Fact]]
"""Reads an order's goal (atoms or a goal's name, in the target's words) into atoms
of the task; raises :class:`~plan_bridge.errors.PlanBridgeError` saying what is wrong."""


class OrderExecutive(Executive):
    """An executive that serves the orders of ``orders`` (see the module documentation).

    ``goal_of`` reads an order's goal; ``per_robot`` and ``attempts`` are the horizon
    and the plans given up for an order before it fails. The other arguments are the
    :class:`~plan_bridge.execution.executive.Executive`'s; the task's own goal is not
    used.
    """

    def __init__(
        self,
        task: PlanningTask,
        *args: Any,
        orders: OrderBook,
        goal_of: GoalReader,
        upkeep: UpkeepGoals | None = None,
        per_robot: int = DEFAULT_PER_ROBOT,
        attempts: int = DEFAULT_ATTEMPTS,
        **kwargs: Any,
    ) -> None:
        super().__init__(task, *args, **kwargs)
        if per_robot < 1 or attempts < 1:
            raise ValueError(
                f"per_robot and attempts must be 1 or more, got {per_robot}, {attempts}"
            )
        self.orders = orders
        self.goal_of = goal_of
        self.upkeep = upkeep
        self.per_robot = per_robot
        self.attempts = attempts
        view = self.task_view
        #: The robots orders are assigned to (the world's agents: agents_of).
        self.robots = agents_of(task, view.objects() if view is not None else None)
        self._t0 = 0.0
        self._woken = threading.Event()
        self._planned_for: tuple[str, ...] = ()
        self._planned_upkeep: tuple[Fact, ...] = ()
        # Plan position -> the orders that step serves, for the plan in force.
        self._serves: dict[int, tuple[str, ...]] = {}
        self._serves_lock = threading.Lock()
        # Orders left out of the horizon until another ends (they conflict with it).
        self._deferred: set[str] = set()
        self.busy_s: dict[str, float] = {}
        """Seconds of the mission's clock each robot spent in steps."""
        self._in_steps: dict[int, tuple[tuple[str, ...], float]] = {}
        self.elapsed_s = 0.0
        """The mission's clock at its end (seconds since it began)."""
        self.benched: dict[str, float] = {}
        """Robots left out of plans (the planner is told nothing of them) until a time
        of the mission's clock: their step failed past recovery."""
        self.robots_gone: Callable[[], Collection[str]] | None = None
        """The robots that are gone now (a robot node whose process died: ``plan-bridge
        run --ros``), left out of plans while they are gone; None: every robot stays."""
        self._announced_gone: frozenset[str] = frozenset()
        orders.add_waker(self._wake)
        orders.add_listener(self._order_changed)
        self.hold.alarm = self._alarm

    def run_children(self) -> str | None:
        outcome = super().run_children()
        # Reached: every order that was taken on is done (refused ones were never).
        counts = self.orders.counts()
        self.report.goal_reached = outcome == "succeeded" and not counts["failed"]
        return outcome

    # -- the clock ------------------------------------------------------------------------------
    def now(self) -> float:
        """The mission's clock: seconds since the mission began (simulated seconds in a
        simulated world)."""
        return clock_of(self.world).now() - self._t0

    def desk(self) -> OrderDesk:
        """Order requests for this mission (control API, viewer, ROS 2)."""
        return OrderDesk(self.orders, self.now)

    def _alarm(self) -> float | None:
        at = self.orders.next_arrival()
        return None if at is None else self._t0 + at

    def _wake(self) -> None:
        self._woken.set()
        if self.is_running():
            self.hold.request()

    # -- the loop ---------------------------------------------------------------------------------
    def _mission(self) -> str:
        self._t0 = clock_of(self.world).now()
        self.busy_s = {}
        self.benched = {}
        resume, self._resume = self._resume, None
        if resume is not None:
            self._take_up(resume)
        recovery = self._begin_mission()
        recovery.replanner.restrict = self._without_benched
        self._sense()
        plan: list[PlanStep] = []
        self._planned_for = ()
        try:
            while True:
                self._check_preempt()
                if self.operator is not None and self.operator.pending() is not None:
                    plan = self.operator.take(self, plan)
                self._take_orders()
                horizon = self._horizon()
                if not horizon and self._deferred:
                    self._deferred.clear()  # nothing else to wait for: try them again
                    continue
                if self.orders.finished():
                    self.report.explanation = "every order is accounted for: " + self._tally()
                    self.decide("done", self.report.explanation)
                    return "succeeded"
                upkeep = self._upkeep()
                if not horizon and not upkeep:
                    self._idle()
                    plan = []
                    continue
                ids = tuple(s.id for s in horizon)
                if not plan or (ids, upkeep) != (self._still_planned(), self._planned_upkeep):
                    plan = self._plan_for(horizon, upkeep)
                    if not plan:
                        continue
                plan = self._run_for_orders(plan, recovery)
        finally:
            self.elapsed_s = self.now()
            self.report.orders = self.figures()

    def _run_for_orders(self, plan: list[PlanStep], recovery: Recovery) -> list[PlanStep]:
        """Run ``plan``; the plan to go on with ([]: plan again for the orders)."""
        first = self._next_label
        self._assign(plan, first)
        outcome, failed = self._run_plan(plan, first)
        self._next_label = max(self._records, default=first - 1) + 1
        self._sense(
            [
                r.step
                for r in self._records.values()
                if r.outcome == "aborted" and r.by_user and not r.observed
            ]
        )
        self._settle()
        if self.preempt_requested():
            self.decide("stop", "preempted")
            raise MissionEnded("preempted", "preempted")
        if self.operator is not None and self.operator.pending() is not None:
            return plan
        if self._knowledge_pending() or outcome == "succeeded":
            return []
        if outcome == "preempted":  # held: orders arrived or were cancelled
            return []
        if failed is None and not self._open_in_plan():
            return []  # the plan's orders are done (or gone)
        reason, rest, record = self._what_failed(
            plan, first, failed, "the plan finished but its orders' goals do not hold"
        )
        self._retask()
        try:
            return list(recovery.recover(rest, reason, record))
        except MissionEnded as ended:
            if ended.outcome == "preempted":
                raise
            culprits = self._serving(first + failed) if failed is not None else ()
            self._give_up(culprits or self._planned_for, ended.explanation)
            if failed is not None:
                self._bench([a for a in plan[failed].arguments if a in self.robots])
            return []

    def _replan_or_give_up(self, horizon: Sequence[OrderState], reason: str, **how: Any) -> Any:
        """``replanner.plan(reason, **how)``; None when a budget ran out (the horizon's
        orders are given up on)."""
        replanner = self._replanner
        assert replanner is not None
        try:
            return replanner.plan(reason, **how)
        except MissionEnded as ended:
            if ended.outcome == "preempted":
                raise
            self._give_up([s.id for s in horizon], ended.explanation)
            return None

    # -- orders in and out --------------------------------------------------------------------
    def _take_orders(self) -> None:
        """Accept or refuse the orders that have arrived, take cancels into account,
        and mark done those whose goal holds."""
        self.hold.clear()
        self._woken.clear()
        now = self.now()
        for order in self.orders.arrivals(now):
            try:
                atoms = tuple(self.goal_of(order.goal))
            except PlanBridgeError as exc:
                self.orders.refuse(order.id, str(exc), now)
                continue
            self.orders.accept(order.id, atoms, now)
        self._settle()

    def _mark_done(self) -> None:
        """Orders whose goal holds in the belief are done (from any thread)."""
        facts = self.belief.facts
        now = self.now()
        for state in self.orders.open_orders():
            if all(atom in facts for atom in state.atoms):
                try:
                    self.orders.done(state.id, now)
                except OrderBookError:
                    continue  # cancelled meanwhile

    def _settle(self) -> None:
        """Mark orders done; when the open orders changed, the budgets start afresh."""
        self._mark_done()
        if self.orders.take_changed():
            self._deferred.clear()  # an order ended: the deferred ones may fit now
            if self._replanner is not None:
                self._replanner.new_window()

    def _horizon(self) -> list[OrderState]:
        """The open orders to plan for now: those under way first (their robots keep
        them), then by priority and arrival."""
        # per_robot orders for each robot that plans can use (not benched, not gone)
        cap = max(1, len(self.robots - self._out_now())) * self.per_robot
        open_orders = sorted(
            (s for s in self.orders.open_orders() if s.id not in self._deferred),
            key=lambda s: s.status is not OrderStatus.ACTIVE,
        )
        chosen, rest = open_orders[:cap], open_orders[cap:]
        now = self.now()
        for state in rest:
            if state.status is not OrderStatus.QUEUED:
                self.orders.requeue(state.id, now, "orders of a higher priority came first")
        return chosen

    def _idle(self) -> None:
        """Wait for the next order (the clock moves to it), a live one, or a preempt."""
        clock = clock_of(self.world)
        at = self.orders.next_arrival()

        def interrupted() -> bool:
            operator = self.operator
            return (
                self.preempt_requested()
                or self._woken.is_set()
                or (operator is not None and operator.pending() is not None)
            )

        if at is not None:
            self.decide("wait", f"no open order; the next arrives at {at:g} s")
            clock.sleep_until(self._t0 + at, interrupted)
            return
        self.decide("wait", "no open order; waiting for orders")
        while not interrupted():
            self._woken.wait(0.05)

    # -- plans for orders -------------------------------------------------------------------------
    def _set_goal(self, atoms: Sequence[Fact]) -> None:
        goal = tuple(dict.fromkeys(atoms))
        if self.task_view is not None:
            self._goal = goal
            self._retask()
        else:
            self._use_task(task_with_goal(self.task, goal))

    def _upkeep(self) -> tuple[Fact, ...]:
        """The robots' own goals now (a charge for a robot low on battery)."""
        if self.upkeep is None:
            return ()
        facts = self.belief.facts
        out = self._out_now()  # no charge for a robot left out of plans
        return tuple(a for a in self.upkeep(facts, values_of(facts)) if out.isdisjoint(a[1:]))

    def _plan_for(self, horizon: list[OrderState], upkeep: tuple[Fact, ...] = ()) -> list[PlanStep]:
        """A plan for the orders of ``horizon`` and the robots' ``upkeep``; [] when none
        (orders were refused, failed or deferred: the loop looks again)."""
        self._planned_for = tuple(s.id for s in horizon)
        self._planned_upkeep = upkeep
        names = ", ".join(s.id for s in horizon) or "none"
        result = None
        if upkeep:
            self._set_goal([*(a for s in horizon for a in s.atoms), *upkeep])
            kept = " ".join(format_fact(a) for a in upkeep)
            result = self._replan_or_give_up(horizon, f"orders {names}, and {kept}")
            if result is not None and not result.solved:
                self.decide("upkeep", f"no plan with {kept}: planning the orders alone")
                self._planned_upkeep = ()
        if result is None or not result.solved:
            if not horizon:
                return []
            self._set_goal([a for s in horizon for a in s.atoms])
            result = self._replan_or_give_up(horizon, f"orders {names}")
        if result is not None and result.solved:
            return list(result.actions)
        self._planned_for = ()
        if result is None:
            return []
        self.decide("orders", f"no plan for orders {names} together: {result.explanation}")
        if len(horizon) == 1:
            self._no_plan_for(horizon[0], result)
            return []
        unplanned = False
        for state in horizon:
            self._set_goal(state.atoms)
            alone = self._replan_or_give_up([state], f"order {state.id} alone", final=False)
            if alone is not None and not alone.solved:
                self._no_plan_for(state, alone)
                unplanned = True
        if not unplanned:
            # Each has a plan alone, not all together: the last one waits until
            # another ends.
            self._deferred.add(horizon[-1].id)
            self.decide("orders", f"order {horizon[-1].id} waits: it conflicts with the others")
        return []

    def _no_plan_for(self, state: OrderState, result: Any) -> None:
        """No plan reaches ``state``'s goal: refused when it never started, else failed."""
        why = f"no plan for it ({result.status.value}): {result.explanation}"
        gone = self._gone()
        out = self._out_now(gone)
        things = {arg for atom in state.atoms for arg in atom[1:]}
        # What a robot left out of plans has of the order's things (a parcel it carries).
        held = sorted(
            f"{format_fact(fact)}: {fact[1]} {'gone' if fact[1] in gone else 'benched'}"
            for fact in self.belief.facts
            if len(fact) > 2 and fact[1] in out and things.intersection(fact[2:])
        )
        if held:
            why += f" (left out of plans with its robot: {'; '.join(held)})"
        now = self.now()
        if state.started is None:
            self.orders.refuse(state.id, f"no robot can reach it: {why}", now)
        else:
            self.orders.fail(state.id, why, now)

    def _assign(self, plan: list[PlanStep], first: int) -> None:
        """The orders of the horizon are assigned to the robots whose steps serve them."""
        open_orders = {s.id: s for s in self.orders.open_orders()}
        wanted = {i: open_orders[i].atoms for i in self._planned_for if i in open_orders}
        work = order_work(plan, wanted, self.model, self.belief.facts, self.robots)
        serves: dict[int, list[str]] = {}
        now = self.now()
        for order_id, done_by in work.items():
            try:
                self.orders.assign(order_id, done_by.robots, now)
            except OrderBookError:
                continue  # cancelled meanwhile (from another thread)
            for position in done_by.steps:
                serves.setdefault(first + position, []).append(order_id)
        with self._serves_lock:
            self._serves = {i: tuple(ids) for i, ids in serves.items()}

    def _still_planned(self) -> tuple[str, ...]:
        """The orders the plan in force was made for that are still open (one that
        ended since needs no new plan)."""
        open_ids = {s.id for s in self.orders.open_orders()}
        return tuple(i for i in self._planned_for if i in open_ids)

    def _serving(self, index: int) -> tuple[str, ...]:
        with self._serves_lock:
            return self._serves.get(index, ())

    def _open_in_plan(self) -> bool:
        open_ids = {s.id for s in self.orders.open_orders()}
        return any(i in open_ids for i in self._planned_for)

    def _give_up(self, order_ids: Sequence[str], reason: str) -> None:
        """The plan for ``order_ids`` was given up: each goes back to the queue (another
        robot may take it), or fails after :attr:`attempts` plans."""
        now = self.now()
        for order_id in dict.fromkeys(order_ids):
            state = self.orders.get(order_id)
            if state.final:
                continue
            if self.orders.note_attempt(order_id) >= self.attempts:
                self.orders.fail(order_id, reason, now)
            else:
                self.orders.requeue(order_id, now, f"its plan was given up: {reason}")
        if self._replanner is not None:
            self._replanner.new_window()
        self._planned_for = ()

    # -- checkpoints -----------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        """The executive's checkpoint, with the book and the mission's clock."""
        data = super().snapshot()
        data["orders"] = self.orders.snapshot()
        data["mission"] = {
            "t0": self._t0,
            "benched": dict(self.benched),
            "busy_s": dict(self.busy_s),
        }
        return data

    def _take_up(self, snapshot: dict[str, Any]) -> None:
        """Continue from a checkpoint: the belief, the report, the book and the clock;
        the open orders are planned again from the belief (nothing done is redone)."""
        self._restore(snapshot)
        self._resume_plan_zero = None  # the next plan is a new one, not the killed one's
        if "orders" in snapshot:
            self.orders.restore(snapshot["orders"])
        mission = snapshot.get("mission", {})
        self._t0 = float(mission.get("t0", self._t0))
        self.benched = {str(r): float(t) for r, t in mission.get("benched", {}).items()}
        self.busy_s = {str(r): float(t) for r, t in mission.get("busy_s", {}).items()}

    # -- robots left out ----------------------------------------------------------------------
    def _gone(self) -> frozenset[str]:
        return frozenset(self.robots_gone()) if self.robots_gone is not None else frozenset()

    def _bench(self, robots: Sequence[str]) -> None:
        """Leave ``robots`` out of plans for :data:`BENCH_S` (unless no robot would be left)."""
        now = self.now()
        gone = self._gone()
        available = {r for r in self.robots if self.benched.get(r, -1.0) <= now and r not in gone}
        robots = [r for r in robots if r in available]
        if not robots or available <= set(robots):
            return
        for robot in robots:
            self.benched[robot] = now + BENCH_S
        self.decide(
            "bench",
            f"{', '.join(robots)} left out of plans until {now + BENCH_S:g} s: its step "
            f"failed past recovery; the other robots take its orders",
        )

    def _out_now(self, gone: frozenset[str] | None = None) -> set[str]:
        """The robots left out of plans now: benched, or gone (``gone``: as just asked)."""
        now = self.now()
        benched = {r for r, until in self.benched.items() if until > now}
        return benched | (self._gone() if gone is None else gone)

    def _without_benched(self, facts: FactSnapshot) -> FactSnapshot:
        """``facts`` without those of the robots benched or gone now."""
        gone = self._gone()
        if gone - self._announced_gone:
            self.decide(
                "gone",
                f"{', '.join(sorted(gone - self._announced_gone))} gone (its robot node is "
                f"not there): left out of plans, the other robots take its orders",
            )
        self._announced_gone = gone
        out = self._out_now(gone)
        if not out:
            return facts
        kept = [f for f in facts if not any(arg in out for arg in f[1:])]
        return FactSnapshot(kept, values_of(facts))

    # -- steps ------------------------------------------------------------------------------------
    def _step_started(self, index: int, step: PlanStep) -> None:
        now = self.now()
        robots = tuple(a for a in step.arguments if a in self.robots)
        with self._serves_lock:
            self._in_steps[index] = (robots, now)
            serving = self._serves.get(index, ())
        for order_id in serving:
            try:
                self.orders.activate(order_id, now)
            except OrderBookError:
                continue  # ended meanwhile (cancelled)

    def _step_finished(self, record: StepRecord) -> None:
        now = self.now()
        with self._serves_lock:
            robots, began = self._in_steps.pop(record.index, ((), now))
            for robot in robots:
                self.busy_s[robot] = self.busy_s.get(robot, 0.0) + max(0.0, now - began)
        if record.outcome == "succeeded":  # (a step that did not start holds the belief)
            self._mark_done()  # before the checkpoint the step's end writes
        super()._step_finished(record)

    def _order_changed(self, state: OrderState) -> None:
        self._announce(
            OrderChanged,
            order=state.id,
            status=state.status.value,
            goal=state.order.goal,
            at=round(self.now(), 3) if self.is_running() else 0.0,
            robots=state.robots,
            reason=state.reason,
            priority=state.order.priority,
            arrived=state.arrived,
            latency=None if state.latency is None else round(state.latency, 3),
            origin=state.order.origin,
        )
        if state.status in (OrderStatus.CANCELLED,) and state.id in self._planned_for:
            self.hold.request()

    def figures(self) -> dict[str, Any]:
        """The book's summary, and each robot's share of the mission's time in steps."""
        return self.orders.summary(self.elapsed_s, self.busy_s, self.robots)

    def _tally(self) -> str:
        counts = self.orders.counts()
        shown = [f"{n} {status}" for status, n in counts.items() if n and status != "late"]
        return ", ".join(shown) or "no orders"

    # -- operator ---------------------------------------------------------------------------------
    def replan_now(self, reason: str, task: PlanningTask | None = None) -> list[PlanStep]:
        """An operator's replan plans for the orders again; an operator's new goal is
        an order (``operator-N``)."""
        if task is not None:
            text = " ".join(format_fact(f) for f in task.goal_facts)
            self.orders.submit(text, origin="operator", even_if_closed=True)
        self._planned_for = ()
        return []
