"""The planning layer's result types and the :class:`Planner` protocol, in one place.

Every planner (:mod:`.planner`'s unified-planning engines, :mod:`.engines`' ``auto``
and warm search, :mod:`.portfolio`'s racing configurations) takes a
:class:`~plan_bridge.pddl.task.PlanningTask` and answers a :class:`PlanResult`: a
:class:`PlanStatus` and, when solved, the plan's :class:`PlanStep` list. The rest of
plan_bridge (execution, missions, the CLI) needs nothing else from this package to
read a plan.
"""

from __future__ import annotations

import enum
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeGuard, runtime_checkable

from plan_bridge.pddl.task import Fact, FactLike, PlanningTask, format_fact

__all__ = [
    "CancellablePlanner",
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "accepts_cancel",
    "snapshot_values",
]


class PlanStatus(str, enum.Enum):
    """What a solve ended with."""

    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    TIMEOUT = "timeout"
    ERROR = "error"
    UNSUPPORTED = "unsupported"


@dataclass(frozen=True)
class PlanStep:
    """One ground action of a plan: ``PlanStep("pick", ("cup", "table"))``.

    Steps of a temporal plan also carry their planned ``start`` and ``duration``
    (plan time, seconds); they do not take part in equality, so a step is the same
    action whenever it is planned.
    """

    action: str
    arguments: tuple[str, ...] = ()
    start: float | None = field(default=None, compare=False)
    duration: float | None = field(default=None, compare=False)

    def __str__(self) -> str:
        return "(" + " ".join((self.action, *self.arguments)) + ")"


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one solve."""

    status: PlanStatus
    actions: list[PlanStep] = field(default_factory=list)
    planner: str = ""
    planning_time_s: float = 0.0
    """Wall-clock time of the whole ``solve`` call (PDDL writing, worker, analysis)."""
    explanation: str = ""
    """Why there is no plan (empty when solved)."""
    warnings: tuple[str, ...] = ()
    """Warnings of unified-planning and the engine during this solve."""
    unreachable_goals: tuple[Fact, ...] = ()
    """Goal atoms unreachable under delete relaxation (when that was the reason)."""
    engine_status: str = ""
    """The engine's own status (UP ``PlanGenerationResultStatus`` name)."""
    engine_time_s: float = 0.0
    """Time spent in the engine inside the worker."""
    log: str = ""
    """The tail of the engine's log."""
    problem_reused: bool = False
    """True when the worker derived the problem from one it had parsed before (a
    replan's fast path: no PDDL parsing)."""

    @property
    def solved(self) -> bool:
        return self.status is PlanStatus.SOLVED

    def plan_strings(self) -> list[str]:
        return [str(step) for step in self.actions]

    @property
    def temporal(self) -> bool:
        """Whether the plan is time-triggered (its steps have start times)."""
        return any(step.start is not None for step in self.actions)

    @property
    def makespan(self) -> float | None:
        """When the last action of a temporal plan ends (plan time); None otherwise."""
        if not self.temporal:
            return None
        return max(((s.start or 0.0) + (s.duration or 0.0) for s in self.actions), default=0.0)

    def to_json(self) -> dict[str, Any]:
        """A JSON-serialisable summary (the shape of ``plan-bridge plan --json``)."""
        return {
            "status": self.status.value,
            "planner": self.planner,
            "planning_time_s": round(self.planning_time_s, 4),
            "plan_length": len(self.actions),
            "plan": self.plan_strings(),
            "explanation": self.explanation,
            "unreachable_goals": [format_fact(goal) for goal in self.unreachable_goals],
            "warnings": list(self.warnings),
            "engine_status": self.engine_status,
            **self._timing_json(),
        }

    def _timing_json(self) -> dict[str, Any]:
        if not self.temporal:
            return {}
        return {
            "actions": [
                {"action": str(step), "start": step.start, "duration": step.duration}
                for step in self.actions
            ],
            "makespan": self.makespan,
        }


@runtime_checkable
class Planner(Protocol):
    """Anything that turns a :class:`PlanningTask` into a :class:`PlanResult`."""

    @property
    def name(self) -> str: ...

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
    ) -> PlanResult:
        """Plan for ``task``; ``initial_state`` (true ground facts) replaces the
        task's initial state for this solve (closed world), and ``goal`` (ground
        atoms) replaces its goal by their conjunction."""
        ...


def snapshot_values(
    initial_state: Iterable[FactLike] | None, values: Mapping[Fact, float] | None
) -> Mapping[Fact, float] | None:
    """``values``, or the numbers a belief's snapshot carries when ``initial_state`` is
    one (:class:`~plan_bridge.belief.FactSnapshot`) and none were given."""
    carried = getattr(initial_state, "values", None)
    if values is None and isinstance(carried, Mapping):
        return carried
    return values


class CancellablePlanner(Planner, Protocol):
    """A :class:`Planner` whose ``solve`` also takes ``cancel``: an event that stops the
    solve (the engines of this package kill their planner process)."""

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
        cancel: threading.Event | None = None,
    ) -> PlanResult: ...


def accepts_cancel(planner: Planner) -> TypeGuard[CancellablePlanner]:
    """Whether ``planner.solve`` takes ``cancel=`` (:class:`CancellablePlanner`)."""
    import inspect

    try:
        return "cancel" in inspect.signature(planner.solve).parameters
    except (TypeError, ValueError):
        return False
