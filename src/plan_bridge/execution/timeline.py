"""The timeline of a temporal run: when each action was planned and when it ran.

Every step of a temporal plan emits :class:`ActionStarted` and :class:`ActionEnded`
with its planned and actual (wall seconds since the dispatch began) times, on the
same stream as every other event: journal, viewer timeline (the Gantt view) and study
read the same records. :class:`TimelineRecorder` listens to them for a run's planned
and executed makespans.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from plan_bridge.execution.events import PlanComputed
from smach.introspection.events import Event

__all__ = ["ActionEnded", "ActionStarted", "TimelineRecorder", "Timing"]


@dataclass(slots=True, kw_only=True)
class ActionStarted(Event):
    """A step of a temporal plan started (``path`` is the step's state)."""

    kind: ClassVar[str] = "action_started"
    index: int
    action: str
    planned_start: float
    planned_duration: float
    actual_start: float
    """Wall seconds since the dispatch began."""
    time_scale: float = 0.0
    """Wall seconds per plan second of the dispatch (0: as fast as it goes)."""


@dataclass(slots=True, kw_only=True)
class ActionEnded(Event):
    """A step of a temporal plan ended (``path`` is the step's state)."""

    kind: ClassVar[str] = "action_ended"
    index: int
    action: str
    outcome: str
    planned_start: float
    planned_duration: float
    actual_start: float
    actual_end: float


@dataclass
class Timing:
    """Planned and actual times of one step (actual: wall seconds since dispatch)."""

    planned_start: float
    planned_duration: float
    actual_start: float | None = None
    actual_end: float | None = None


class TimelineRecorder:
    """A listener for the makespans of a run: planned (of the first temporal plan) and
    executed (wall seconds from the first action's start to the last one's end)."""

    def __init__(self) -> None:
        self.makespan_planned: float | None = None
        self._first: float | None = None
        self._last: float | None = None

    def __call__(self, event: Event) -> None:
        if isinstance(event, PlanComputed):
            if self.makespan_planned is None and event.makespan is not None:
                self.makespan_planned = event.makespan
        elif isinstance(event, ActionStarted):
            if self._first is None:
                self._first = event.time
        elif isinstance(event, ActionEnded):
            self._last = event.time

    @property
    def temporal(self) -> bool:
        return self.makespan_planned is not None

    @property
    def makespan_executed(self) -> float | None:
        if self._first is None or self._last is None:
            return None
        return self._last - self._first
