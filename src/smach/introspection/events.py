"""The one event stream of smach.

Every container reports what happens while it runs as typed events: started, state
entered/exited, transition, preempt requested/serviced, userdata written,
terminated, error. Each carries the path of what it is about (``/ROOT/FETCH/PICK``),
a monotonic timestamp and the name of the thread. Everything that watches execution
(journal, viewers, SMACH callbacks, loggers, metrics) is a listener of this stream.

Events are only built when somebody listens: containers check
``bus.listeners`` (a plain list) before constructing one.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, ClassVar

__all__ = [
    "ContainerStarted",
    "ContainerTerminated",
    "ErrorRaised",
    "Event",
    "EventBus",
    "Listener",
    "PreemptRequested",
    "PreemptServiced",
    "StateEntered",
    "StateExited",
    "Transition",
    "UserdataWritten",
    "stamp",
]


def stamp() -> tuple[float, str]:
    """The (monotonic time, thread name) pair every event carries."""
    return time.monotonic(), threading.current_thread().name


@dataclass(slots=True, kw_only=True)
class Event:
    """Base of every event: what it is about (``path``), when, and in which thread."""

    kind: ClassVar[str] = "event"
    path: str
    time: float
    thread: str

    def to_dict(self) -> dict[str, Any]:
        """Plain data (values are left as they are; serialisers summarise them)."""
        data: dict[str, Any] = {"kind": self.kind}
        for f in fields(self):
            data[f.name] = getattr(self, f.name)
        return data


@dataclass(slots=True, kw_only=True)
class ContainerStarted(Event):
    """A container began an execution; ``path`` is the container."""

    kind: ClassVar[str] = "container_started"
    container_type: str
    initial_states: tuple[str, ...]


@dataclass(slots=True, kw_only=True)
class StateEntered(Event):
    """A child state is about to execute; ``path`` is the child."""

    kind: ClassVar[str] = "state_entered"
    label: str


@dataclass(slots=True, kw_only=True)
class StateExited(Event):
    """A child state returned ``outcome``; ``path`` is the child."""

    kind: ClassVar[str] = "state_exited"
    label: str
    outcome: str | None


@dataclass(slots=True, kw_only=True)
class Transition(Event):
    """A container moved from one child to the next; ``path`` is the container."""

    kind: ClassVar[str] = "transition"
    source: str
    outcome: str
    target: str


@dataclass(slots=True, kw_only=True)
class PreemptRequested(Event):
    """Somebody asked the state at ``path`` to stop."""

    kind: ClassVar[str] = "preempt_requested"


@dataclass(slots=True, kw_only=True)
class PreemptServiced(Event):
    """The state at ``path`` acknowledged a preempt request."""

    kind: ClassVar[str] = "preempt_serviced"


@dataclass(slots=True, kw_only=True)
class UserdataWritten(Event):
    """A state wrote ``key`` of the container at ``path``; ``value`` is the live object."""

    kind: ClassVar[str] = "userdata_written"
    key: str
    value: Any
    writer: str


@dataclass(slots=True, kw_only=True)
class ContainerTerminated(Event):
    """A container finished with ``outcome`` (``None`` on shutdown)."""

    kind: ClassVar[str] = "container_terminated"
    terminal_states: tuple[str, ...]
    outcome: str | None


@dataclass(slots=True, kw_only=True)
class ErrorRaised(Event):
    """An error left the container at ``path``."""

    kind: ClassVar[str] = "error"
    error_type: str
    message: str


Listener = Callable[[Event], object]


class EventBus:
    """The listeners of one tree of states; shared by every state of the tree."""

    __slots__ = ("_lock", "listeners", "log_info", "preempt_seen")

    def __init__(self) -> None:
        # Whether the current top-level run writes INFO log lines (see Container._begin).
        self.log_info = False
        # Set when any state of the tree got a preempt request, so that the end of a
        # top-level run only walks the tree to clear flags when there can be some.
        self.preempt_seen = False
        # Replaced, never mutated in place, so emitters iterate a stable list
        # without taking the lock.
        self.listeners: list[Listener] = []
        self._lock = threading.Lock()

    def add(self, listener: Listener) -> None:
        with self._lock:
            self.listeners = [*self.listeners, listener]

    def remove(self, listener: Listener) -> None:
        with self._lock:
            # == and not `is`: each access to obj.method makes a new bound method.
            self.listeners = [lst for lst in self.listeners if lst != listener]

    def __getstate__(self) -> dict[str, Any]:
        # Listeners watch a live run (files, sockets, viewers): a copy starts without.
        return {"preempt_seen": False}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.listeners = []
        self._lock = threading.Lock()
        self.preempt_seen = bool(state.get("preempt_seen", False))
        self.log_info = False

    def emit(self, event: Event) -> None:
        """Deliver ``event`` to every listener.

        A listener that raises is removed (and reported once through
        ``smach.logerr``): watching must never break the robot's mission.
        """
        for listener in self.listeners:
            try:
                listener(event)
            except Exception as exc:
                self.remove(listener)
                import smach

                smach.logerr(f"event listener {listener!r} raised {exc!r}; it was detached")
