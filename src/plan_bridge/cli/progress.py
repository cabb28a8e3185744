"""What ``plan-bridge run`` prints while a mission runs and after it: the progress
lines (:class:`ProgressPrinter`) and the summary (:func:`summary_lines`).

One line per step, per plan and per recovery:

* a step's line comes when it ends; a step of a temporal plan also shows when the
  plan starts it and for how long (plan seconds), and its line waits for the lines
  of the steps planned before it, so the lines follow the plan's order (steps that
  never ran hold nothing back once the plan's run is over);
* a plan's line says why it was computed (the initial plan, a replan, a repair) and,
  for a temporal plan, its makespan; a repair the executive rejects is not shown as a
  plan (``-v`` shows it, with why it was rejected);
* a recovery's line names the decision and its reason; when several steps of one
  plan failed (concurrent or temporal steps), each one after the first gets a
  ``[recover]`` line that says what becomes of it.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from smach.introspection.events import Event

__all__ = ["ProgressPrinter", "summary_lines", "summary_text"]


def _count(n: int, one: str, many: str) -> str:
    return f"{n} {one if n == 1 else many}"


def summary_lines(outcome: str | None, report: Any, faults: int | None) -> list[str]:
    """The summary of a run: the outcome, then a few indented lines (actions,
    recovery, time, and the reason when the goal was not reached)."""
    reached = "goal reached" if report.goal_reached else "goal NOT reached"
    if getattr(report, "orders", None):
        reached = "no order failed" if report.goal_reached else "an order FAILED"
    actions = f"  actions: {report.actions_executed} run, {report.actions_failed} failed" + (
        f"; {_count(faults, 'fault', 'faults')} injected" if faults is not None else ""
    )
    recovered = [
        _count(report.retries, "retry", "retries"),
        _count(report.variants_tried, "skill variant", "skill variants"),
        _count(report.continues, "continue", "continues"),
        _count(report.repairs, "repair", "repairs")
        + (f" adopted ({report.repair_attempts} planned)" if report.repair_attempts else ""),
        _count(report.replans, "replan", "replans"),
        _count(report.holds, "hold", "holds"),
    ]
    counts = (
        report.retries,
        report.variants_tried,
        report.continues,
        report.repairs or report.repair_attempts,
        report.replans,
        report.holds,
    )
    recovery = ", ".join(text for text, n in zip(recovered, counts, strict=True) if n) or "none"
    reused = (
        f", {_count(report.plans_reused, 'plan reused', 'plans reused')}"
        if report.plans_reused
        else ""
    )
    calls = _count(report.planner_calls, "planner call", "planner calls")
    lines = [
        f"summary: {outcome} ({reached})",
        actions,
        f"  recovery: {recovery}",
        f"  time: planning {report.planning_time_s:.2f} s ({calls}{reused}), "
        f"execution {report.execution_time_s:.2f} s, total {report.total_time_s:.2f} s",
    ]
    orders = getattr(report, "orders", None)
    if orders:
        lines.insert(1, _orders_line(orders))
    if not report.goal_reached:
        lines.append(f"  reason: {report.explanation}")
    return lines


def _order_line(event: Any) -> str:
    """``[order] soda-1 queued at 12.0 s: (At soda0 counter0_left)`` and the like."""
    status = event.status
    head = f"[order] {event.order} {status} at {event.at:.1f} s"
    if status == "queued":
        return f"{head}: {event.goal}"
    if status in ("assigned", "active"):
        return f"{head} ({', '.join(event.robots) or 'no robot'})"
    if status in ("failed", "refused", "cancelled") or event.reason:
        return f"{head}: {event.reason}" if event.reason else head
    return head


def _orders_line(orders: dict[str, Any]) -> str:
    """The summary's line of a mission of orders."""
    counted = [
        f"{orders[status]} {status}"
        for status in ("done", "failed", "refused", "cancelled", "queued", "assigned", "active")
        if orders.get(status)
    ]
    text = f"  orders: {orders.get('orders', 0)} arrived" + (
        f" ({', '.join(counted)})" if counted else ""
    )
    if orders.get("not_arrived"):
        text += f", {orders['not_arrived']} not arrived"
    if orders.get("late"):
        text += f"; {orders['late']} late"
    if orders.get("latency_p50_s") is not None:
        text += (
            f"; latency p50 {orders['latency_p50_s']:.1f} s, p95 {orders['latency_p95_s']:.1f} s"
        )
    if orders.get("orders_per_hour") is not None:
        text += f"; {orders['orders_per_hour']:.1f} done per hour"
    return text


def summary_text(outcome: str | None, report: Any, faults: int | None) -> str:
    """:func:`summary_lines` joined into one string (no trailing newline)."""
    return "\n".join(summary_lines(outcome, report, faults))


#: What becomes of a failed step that is not the one a recovery decision is about
#: (the executive decides about the first failed step of the plan and goes on with
#: every step not done: see ``Executive._mission`` and ``execution/repair.py``).
_OTHERS = {
    "retry": "it stays in the held plan and runs again",
    "variant": "it stays in the held plan and runs again",
    "hold": "it stays in the held plan and runs again",
    "continue": "it stays in the rest of the plan and runs again",
    "repair": "it stays in the repaired plan and runs again",
}
_REPLACED = "the new plan, made from the belief, replaces it"
_ENDED = "not run again: the mission ended"


class ProgressPrinter:
    """Prints one line per step, per plan and per recovery (see the module doc);
    ``verbose``: also the states each step enters and every decision of the
    executive, and every plan with its full reason.

    Events come from the steps' threads: one lock keeps the lines whole and in order.
    """

    #: Decisions printed only with ``verbose``: what was considered and not done.
    CONSIDERED = frozenset({"repair-skipped", "repair-rejected"})

    def __init__(self, stream: TextIO, *, verbose: bool = False) -> None:
        self.stream = stream
        self.verbose = verbose
        self.total = 0
        self._lock = threading.Lock()
        self._executive = ""  # the executive's path (of its plans and decisions)
        # Temporal plans: planned (start, duration) by step index, and the lines of
        # ended steps held until the steps planned before them have ended: ``_next``
        # is the next step to print (None after a resume, whose first step is not
        # known: then a line waits only for the steps before it that are running).
        self._timing: dict[int, tuple[float, float]] = {}
        self._held: dict[int, str] = {}
        self._temporal = False
        self._next: int | None = None
        self._running: set[int] = set()
        self._last_index = 0
        self._resumed = False
        # Failed steps of the plan in force (index -> "(action) outcome"), and the
        # failed steps a replan is about, told once its result is known.
        self._failed: dict[int, str] = {}
        self._after_replan: dict[int, str] = {}
        # A planned repair, shown once the executive adopts it (else not at all).
        self._repair_plan: str | None = None

    def __call__(self, event: Event) -> None:
        with self._lock:
            lines = self._lines(event)
            if lines:
                self.stream.write("".join(f"{line}\n" for line in lines))
                self.stream.flush()

    def _lines(self, event: Event) -> list[str]:
        from plan_bridge.execution.events import ExecutiveDecision, PlanComputed, StepFinished
        from plan_bridge.execution.temporal import ActionStarted
        from smach.introspection.events import (
            ContainerStarted,
            ContainerTerminated,
            ErrorRaised,
            StateEntered,
        )

        if isinstance(event, StepFinished):
            return self._step_finished(event)
        if isinstance(event, ActionStarted):
            self._timing[event.index] = (event.planned_start, event.planned_duration)
            self._running.add(event.index)
            return []
        plan_machine = f"{self._executive}/PLAN"
        if isinstance(event, ContainerStarted) and event.path == plan_machine:
            # A plan starts running: its steps are numbered on from the last one.
            lines = self._release(everything=True)
            self._temporal = event.container_type == "TemporalDispatch"
            self._next = None if self._resumed else self._last_index + 1
            self._resumed = False
            return lines
        if isinstance(event, (ContainerTerminated, ErrorRaised)) and event.path == plan_machine:
            return self._release(everything=True)  # what never ran holds nothing back
        if isinstance(event, PlanComputed):
            self._executive = event.path
            return self._release(everything=True) + self._plan(event)
        if isinstance(event, ExecutiveDecision):
            self._executive = event.path
            return self._release(everything=True) + self._decision(event)
        if event.kind == "order":
            return [_order_line(event)]
        if isinstance(event, (ContainerTerminated, ErrorRaised)) and event.path == self._executive:
            # The mission ended: whatever is still held, and the failed steps a
            # replan that gave no plan was about.
            lines = self._release(everything=True) + self._others(self._after_replan, _ENDED)
            self._after_replan = {}
            return lines
        if self.verbose and isinstance(event, StateEntered) and "/SKILL/" in event.path:
            return [f"    {event.path}"]
        return []

    # -- steps ---------------------------------------------------------------------------
    def _step_finished(self, event: Any) -> list[str]:
        skill = (
            f" (skill: {event.skill_outcome})"
            if event.skill_outcome and event.outcome != event.skill_outcome
            else ""
        )
        timing = self._timing.pop(event.index, None)
        planned = "" if timing is None else f" planned at {timing[0]:.2f} s for {timing[1]:.2f} s"
        line = (
            f"  step {event.index}: {event.action}{planned} -> {event.outcome}{skill}"
            f" [{event.duration_s * 1000:.0f} ms]"
        )
        if event.outcome in ("aborted", "invalid"):
            self._failed[event.index] = f"{event.action} {event.outcome}"
        self._last_index = max(self._last_index, event.index)
        self._running.discard(event.index)
        if not self._temporal:
            return [line]  # steps in sequence (or in layers): as they end
        self._held[event.index] = line
        return self._release()

    def _release(self, *, everything: bool = False) -> list[str]:
        """The held step lines whose predecessors in the plan have been printed (with
        ``everything``: all of them, the plan's run is over)."""
        if everything:
            self._running.clear()
            ready = sorted(self._held)
        elif self._next is not None:
            ready = []
            while self._next in self._held:
                ready.append(self._next)
                self._next += 1
        else:
            first_running = min(self._running, default=None)
            ready = sorted(i for i in self._held if first_running is None or i < first_running)
        return [self._held.pop(i) for i in ready]

    # -- plans and decisions -------------------------------------------------------------
    def _plan(self, event: Any) -> list[str]:
        repair = event.reason.startswith("repair:")
        initial = event.reason == "initial plan"
        if event.status == "solved":
            makespan = f", makespan {event.makespan:.2f} s" if event.makespan is not None else ""
            count = len(event.steps)
            text = (
                f"{count} step{'' if count == 1 else 's'}{makespan} "
                f"({event.planner}, {event.planning_time_s:.2f} s)"
            )
        else:
            text = f"{event.status}: {event.explanation}"
        if self.verbose:
            # The full reason; a repair's plan is a candidate until the decision.
            lines = [f"[plan] {event.reason}: {text}"]
        elif repair:
            # Shown after the [repair] line if the executive adopts it; a rejected or
            # failed repair is not a plan the mission goes on with.
            self._repair_plan = f"[plan] repair: {text}" if event.status == "solved" else None
            return []
        elif event.status == "solved":
            # A replan's reason is on its [replan] line already.
            lines = [f"[plan] {'initial plan' if initial else 'new plan'}: {text}"]
        else:
            lines = [f"[plan] {'initial plan' if initial else 'no new plan'}: {text}"]
        if event.status == "solved" and not repair:
            self.total = len(event.steps)
            lines += self._others(self._after_replan, _REPLACED)
            self._after_replan = {}
        return lines

    def _decision(self, event: Any) -> list[str]:
        decision = event.decision
        if decision == "resume":
            self._resumed = True
        if decision in self.CONSIDERED:
            self._repair_plan = None
            return [f"[{decision}] {event.reason}"] if self.verbose else []
        lines = [f"[{decision}] {event.reason}"]
        failed, self._failed = self._failed, {}
        # The decision is about the first failed step; the others go on with it.
        others = {i: text for i, text in failed.items() if i != min(failed, default=0)}
        if decision == "repair" and self._repair_plan is not None:
            lines.append(self._repair_plan)
        self._repair_plan = None
        if decision == "replan":
            self._after_replan = {**self._after_replan, **others}  # told with its result
        elif decision == "hold":
            lines += self._others({**self._after_replan, **others}, _OTHERS["hold"])
            self._after_replan = {}
        elif decision in _OTHERS:
            lines += self._others(others, _OTHERS[decision])
        return lines

    @staticmethod
    def _others(failed: dict[int, str], what: str) -> list[str]:
        return [f"[recover] step {i} {failed[i]} too: {what}" for i in sorted(failed)]
