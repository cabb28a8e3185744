"""The timeline (Gantt) of temporal plans: planned and actual interval of each action.

A temporal plan's dispatcher (``plan_bridge.execution.temporal``) emits
``action_started`` and ``action_ended`` records (recognised here by their ``kind``
only) with each step's planned start and duration (plan seconds, as the planner gave
them) and its actual start and end (wall seconds since that dispatch began). The
:class:`~smach.introspection.model.ViewModel` folds them into :class:`Timeline`
rows; :func:`gantt` lays the rows out on one axis for the page.

**The axis.** When every dispatch ran with a time scale (wall seconds per plan
second, ``--time-scale``; the viewer's default is 0.1), the axis is in **plan
seconds**: an actual time is its wall time divided by the scale, so a step on time
has its actual bar over its planned one, and a late one is drawn to the right of it.
Each dispatch (a new plan after a replan, a retry) starts where the previous one's
wall clock had got to, and its planned bars are placed from that point (its plan's
earliest start there). When a dispatch ran as fast as it goes (time scale 0), wall and
plan seconds cannot be compared: the axis is ``"wall"``, actual bars are in wall
seconds since the first action started and planned bars keep a plan-seconds axis of
their own (each plan laid after the previous one's planned end); the page draws two
axes and says so.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

__all__ = ["MAX_ACTIONS", "Dispatch", "Timeline", "gantt"]

MAX_ACTIONS = 5000
"""Rows kept by the view (the oldest are dropped beyond it)."""
DIGITS = 6
"""Decimals of the positions sent to the page (a microsecond of wall time at most)."""


def _number(value: Any, default: float = 0.0) -> float:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return default


@dataclass(frozen=True, slots=True)
class Dispatch:
    """One run of a temporal plan's dispatcher."""

    container: str
    wall: float
    """Monotonic time at which the dispatch began."""
    scale: float
    plan: int
    """How many plans the view had seen when it began (the plan it runs)."""
    plan_origin: float
    """The earliest planned start of its steps seen so far (plan seconds)."""


@dataclass(frozen=True, slots=True)
class Action:
    """One started action (a step started again is a new row)."""

    index: int
    action: str
    path: str
    dispatch: int
    planned_start: float
    planned_duration: float
    started: float
    """Monotonic time of its start."""
    ended: float | None = None
    outcome: str = "running"


@dataclass
class Timeline:
    """The folded ``action_started``/``action_ended`` records of a run (values are
    never changed in place: :meth:`copy` is one level deep)."""

    dispatches: list[Dispatch] = field(default_factory=list)
    actions: list[Action] = field(default_factory=list)
    current: dict[str, int] = field(default_factory=dict)
    """Dispatcher path -> its current dispatch (forgotten when it starts again)."""

    def copy(self) -> Timeline:
        return Timeline(list(self.dispatches), list(self.actions), dict(self.current))

    def container_started(self, path: str) -> None:
        self.current.pop(path, None)

    def started(self, path: str, record: Mapping[str, Any], plan: int) -> None:
        t = _number(record.get("time"))
        container = path.rsplit("/", 1)[0]
        planned_start = _number(record.get("planned_start"))
        number = self.current.get(container)
        if number is None:
            number = len(self.dispatches)
            self.dispatches.append(
                Dispatch(
                    container,
                    t - _number(record.get("actual_start")),
                    max(0.0, _number(record.get("time_scale"))),
                    plan,
                    planned_start,
                )
            )
            self.current[container] = number
        elif planned_start < self.dispatches[number].plan_origin:
            self.dispatches[number] = replace(self.dispatches[number], plan_origin=planned_start)
        action = Action(
            index=int(_number(record.get("index"))),
            action=str(record.get("action", "")),
            path=path,
            dispatch=number,
            planned_start=planned_start,
            planned_duration=max(0.0, _number(record.get("planned_duration"))),
            started=t,
        )
        self.actions = [*self.actions[-(MAX_ACTIONS - 1) :], action]

    def close(self, path: str, t: float | None, outcome: str, *, below: bool = False) -> None:
        """End the running rows of ``path`` (and of the states below it with ``below``)
        at ``t`` (None: the last moment the timeline saw): the step's own end event was
        not seen (a live viewer that dropped events, or a run killed while the step ran,
        whose root starts again in the resumed run)."""
        if t is None:
            t = max((r.ended or r.started for r in self.actions), default=0.0)
        prefix = path.rstrip("/") + "/"
        for n, row in enumerate(self.actions):
            if row.ended is None and (row.path == path or (below and row.path.startswith(prefix))):
                self.actions[n] = replace(row, ended=max(t, row.started), outcome=outcome)

    def ended(self, path: str, record: Mapping[str, Any]) -> None:
        t = _number(record.get("time"))
        outcome = str(record.get("outcome", ""))
        for n in range(len(self.actions) - 1, -1, -1):
            row = self.actions[n]
            if row.path == path and row.ended is None:
                self.actions[n] = replace(row, ended=t, outcome=outcome)
                return


def gantt(timeline: Timeline, now: float | None) -> dict[str, Any] | None:
    """The rows of the page's Gantt view (None when the run has no temporal plan).

    ``now`` (a monotonic time, the moment shown) ends the bars of running actions.
    Every row has ``p0``/``p1`` (planned interval) and ``a0``/``a1`` (actual), rounded
    to :data:`DIGITS` decimals, on the axis named by ``axis``: ``"plan"`` (plan
    seconds) or ``"wall"`` (actual in wall seconds, planned on a plan-seconds axis of
    its own); see the module doc.
    """
    if not timeline.actions:
        return None
    dispatches = timeline.dispatches
    scaled = all(d.scale > 0 for d in dispatches)
    zero = dispatches[0].wall
    # Where each dispatch begins on the axis: actual (x_actual) and planned (x_plan).
    x_actual: list[float] = []
    x_plan: list[float] = []
    planned_end: list[float] = [0.0] * len(dispatches)
    for row in timeline.actions:
        d = dispatches[row.dispatch]
        end = row.planned_start - d.plan_origin + row.planned_duration
        planned_end[row.dispatch] = max(planned_end[row.dispatch], end)
    for n, d in enumerate(dispatches):
        if n == 0:
            x_actual.append(0.0)
            x_plan.append(0.0)
            continue
        before = dispatches[n - 1]
        if scaled:
            x = x_actual[-1] + (d.wall - before.wall) / before.scale
            x_actual.append(x)
            x_plan.append(x)
        else:
            x_actual.append(d.wall - zero)
            x_plan.append(x_plan[-1] + planned_end[n - 1])
    moment = now if now is not None else max(r.ended or r.started for r in timeline.actions)

    def actual(t: float, n: int) -> float:
        d = dispatches[n]
        return x_actual[n] + (t - d.wall) / d.scale if scaled else t - zero

    rows = []
    for row in timeline.actions:
        d = dispatches[row.dispatch]
        p0 = x_plan[row.dispatch] + row.planned_start - d.plan_origin
        end = row.ended if row.ended is not None else max(moment, row.started)
        rows.append(
            {
                "index": row.index,
                "action": row.action,
                "outcome": row.outcome,
                "dispatch": row.dispatch,
                "plan": d.plan,
                "planned_start": row.planned_start,
                "planned_duration": row.planned_duration,
                "p0": round(p0, DIGITS),
                "p1": round(p0 + row.planned_duration, DIGITS),
                "a0": round(actual(row.started, row.dispatch), DIGITS),
                "a1": round(actual(end, row.dispatch), DIGITS),
                "running": row.ended is None,
            }
        )
    return {
        "axis": "plan" if scaled else "wall",
        "time_scale": dispatches[-1].scale,
        "dispatches": len(dispatches),
        "rows": rows,
    }
