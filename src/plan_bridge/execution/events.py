"""Events of the planning layer, on the same stream as smach's own events."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

from smach.introspection.events import (
    Capture,
    CaptureListener,
    Event,
    SceneChanged,
    captured,
    publish,
    stamp,
)

if TYPE_CHECKING:
    import smach

__all__ = [
    "ExecutiveDecision",
    "ObservationsApplied",
    "PicturedWorld",
    "PlanComputed",
    "StepFinished",
    "WorldScenes",
]


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


# -- pictures of the world: "scene" events ---------------------------------------------------
@runtime_checkable
class PicturedWorld(Protocol):
    """A world that can draw itself (:class:`~plan_bridge.robosim.world.RobosimWorld`)."""

    on_scene: Callable[[str], object] | None
    """Set by :class:`WorldScenes`; the world calls it (with what changed) when its own
    events changed it."""

    def scene(self) -> tuple[str, str]:
        """The picture of the world now: (SVG text, caption)."""
        ...


class WorldScenes:
    """Pictures of a mission's world on its executive's event stream, as
    :class:`~smach.introspection.events.SceneChanged` (``scene``) events: at the start
    (:meth:`show`), at the end of every step, after every change the world's events
    make, and at the end (:meth:`close`). A picture equal to the last one shown is not
    sent again, so a journal grows by what changed only. A picture that fails to draw
    is reported once, and the mission goes on without pictures.
    """

    def __init__(self, executive: smach.Container, world: PicturedWorld) -> None:
        self.executive = executive
        self.world = world
        self.shown = 0
        self._last = ""
        self._lock = threading.Lock()
        self._broken = False
        self._listener = CaptureListener(self._captured)

    @classmethod
    def start(cls, executive: smach.Container, world: object) -> WorldScenes | None:
        """Show the pictures of ``world`` when it draws itself and a journal or a viewer
        watches ``executive`` (else None: nothing is drawn); the first picture now."""
        if not isinstance(world, PicturedWorld) or not captured(executive):
            return None
        scenes = cls(executive, world)
        executive.add_listener(scenes._listener)
        world.on_scene = scenes.show
        scenes.show("start")
        return scenes

    def _captured(self, capture: Capture) -> None:
        if capture[0] is StepFinished:  # (cls, path, time, thread, index, action, outcome, ...)
            self.show(f"after step {capture[4]} {capture[5]}: {capture[6]}")

    def show(self, why: str = "") -> bool:
        """Emit the world's picture now if it differs from the last one; whether it did."""
        if self._broken:
            return False
        with self._lock:
            try:
                svg, caption = self.world.scene()
            except Exception as exc:  # a picture must never break the mission
                self._broken = True
                import smach

                smach.logerr(f"the picture of the world failed: {exc!r}; no more pictures")
                return False
            if svg == self._last:
                return False
            self._last = svg
            self.shown += 1
            t, thread = stamp()
            title = " · ".join(part for part in (caption, why) if part)
            event = SceneChanged(
                path=self.executive.path, time=t, thread=thread, svg=svg, title=title
            )
            publish(self.executive, event)
            return True

    def close(self) -> None:
        """The last picture (if the world changed since), then stop."""
        self.show("end")
        self.executive.remove_listener(self._listener)
        if self.world.on_scene == self.show:
            self.world.on_scene = None
