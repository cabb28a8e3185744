"""Events of the planning layer, on the same stream as smach's own events."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from smach.introspection.events import Event

__all__ = ["ExecutiveDecision", "ObservationsApplied", "PlanComputed", "StepFinished"]


@dataclass(slots=True, kw_only=True)
class PlanComputed(Event):
    """The executive asked the planner for a plan (``path`` is the executive)."""

    kind: ClassVar[str] = "plan_computed"
    reason: str
    planner: str
    status: str
    steps: tuple[str, ...]
    planning_time_s: float
    explanation: str = ""
    makespan: float | None = None
    """When the last action of a temporal plan ends (plan seconds); None if sequential."""


@dataclass(slots=True, kw_only=True)
class ExecutiveDecision(Event):
    """What the executive decided and why (``retry``, ``continue``, ``repair``, ...)."""

    kind: ClassVar[str] = "executive_decision"
    decision: str
    reason: str
    step: str = ""


@dataclass(slots=True, kw_only=True)
class StepFinished(Event):
    """A plan step ended (``path`` is the step's state)."""

    kind: ClassVar[str] = "step_finished"
    index: int
    action: str
    outcome: str
    skill_outcome: str
    duration_s: float


@dataclass(slots=True, kw_only=True)
class ObservationsApplied(Event):
    """Observations of a step changed the belief (``path`` is the step's state)."""

    kind: ClassVar[str] = "observations_applied"
    changed: tuple[str, ...]
