"""The one event stream of smach (moved to the core: :mod:`smach.events`).

The event types, :class:`EventBus` and the capture conversions live in
:mod:`smach.events`, and :func:`publish` / :func:`captured` in :mod:`smach.runtime`;
they are re-exported here, where user code, the journal and plan_bridge import them.
"""

from __future__ import annotations

from smach.events import (
    Capture,
    CaptureListener,
    ContainerStarted,
    ContainerTerminated,
    ErrorRaised,
    Event,
    EventBus,
    Listener,
    PreemptRequested,
    PreemptServiced,
    SceneChanged,
    StateEntered,
    StateExited,
    Transition,
    UserdataWritten,
    event_of,
    field_names,
    stamp,
)
from smach.runtime import captured, publish

__all__ = [
    "Capture",
    "CaptureListener",
    "ContainerStarted",
    "ContainerTerminated",
    "ErrorRaised",
    "Event",
    "EventBus",
    "Listener",
    "PreemptRequested",
    "PreemptServiced",
    "SceneChanged",
    "StateEntered",
    "StateExited",
    "Transition",
    "UserdataWritten",
    "captured",
    "event_of",
    "field_names",
    "publish",
    "stamp",
]
