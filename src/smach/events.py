"""The one event stream of smach: event types and the bus that carries them.

A leaf of the core: this module only publishes and subscribes. What a tree needs
while it runs besides its listeners (runtime control, the preempt and log
switches) is its :class:`smach.runtime.Runtime`.

Every container reports what happens while it runs as typed events: started, state
entered/exited, transition, preempt requested/serviced, userdata written,
terminated, error. Each carries the path of what it is about (``/ROOT/FETCH/PICK``),
a monotonic timestamp and the name of the thread. Everything that watches execution
(journal, viewers, SMACH callbacks, loggers, metrics) is a listener of this stream.

Events are only built when somebody listens: containers check
``bus.listeners`` (a plain list) before constructing one.

Two kinds of listeners exist. Ordinary listeners receive :class:`Event` objects.
A :class:`CaptureListener` (the journal, the live viewer) receives *captures*
instead: plain tuples ``(event class, path, time, thread, *fields)`` with the fields
in declaration order, which cost the executing thread a tuple and not an object
(see :func:`event_of` and :meth:`Event.capture` for the conversions). A container
builds :class:`Event` objects only when an ordinary listener (or a SMACH callback,
or INFO logging) wants them.
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, ClassVar

from smach.log import loggers
from smach.summary import Summary, frozen

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
    "event_of",
    "field_names",
    "stamp",
]

_monotonic = time.monotonic
_current_thread = threading.current_thread


def stamp() -> tuple[float, str]:
    """The (monotonic time, thread name) pair every event carries."""
    return _monotonic(), _current_thread().name


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

    def capture(self) -> Capture:
        """This event as a capture: ``(type(self), path, time, thread, *fields)``.

        Values that could still change are replaced by their
        :class:`~smach.introspection.summary.Summary` (see :class:`CaptureListener`).
        """
        return (type(self), *[frozen(getattr(self, name)) for name in field_names(type(self))])


Capture = tuple[Any, ...]
"""``(event class, path, time, thread, *fields)``: an event as a plain tuple."""

_FIELD_NAMES: dict[type[Event], tuple[str, ...]] = {}


def field_names(cls: type[Event]) -> tuple[str, ...]:
    """The field names of an event class in declaration order (``path``, ``time``, ...)."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in fields(cls))
    return names


def event_of(capture: Capture) -> Event:
    """The :class:`Event` a capture stands for (with summaries for mutable values)."""
    cls: type[Event] = capture[0]
    return cls(**dict(zip(field_names(cls), capture[1:], strict=True)))


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


@dataclass(slots=True, kw_only=True)
class SceneChanged(Event):
    """A picture of the world the tree acts on, as it is now (a ``scene`` record).

    Emitted (with :func:`publish`) by whoever owns a world, when what it shows changed;
    ``path`` is the container that owns the world. ``svg`` is a standalone SVG document,
    ``title`` a caption. Viewers show the newest scene beside the machine (replay: the
    newest as of the moment shown). Records keep ``svg`` whole, not cut like other
    strings: it is the capture's :class:`~smach.introspection.summary.Summary`, which
    journals and viewers write as it is.
    """

    kind: ClassVar[str] = "scene"
    svg: str
    title: str = ""

    def capture(self) -> Capture:
        return (type(self), self.path, self.time, self.thread, Summary(self.svg), self.title)


Listener = Callable[[Event], object]


class CaptureListener:
    """A listener that receives captures (plain tuples) instead of :class:`Event` objects.

    ``capture`` is called with ``(event class, path, time, thread, *fields)`` in the
    emitting thread. Events that happen together (a state machine's ``state_exited``
    and the ``transition`` that follows) may come as one call of ``capture_many`` with
    a tuple of captures, in order; by default it calls ``capture`` for each. Captures
    are cheaper than events (no object is built when every listener of the tree takes
    captures). Their values cannot change: strings, numbers, ``None``, tuples of them,
    or, for anything else (a userdata list, say), a
    :class:`~smach.introspection.summary.Summary` made when the event happened. So a
    capture listener may keep captures and look at them later, from another thread:
    the journal's writer and the viewer's pump do. Called directly with an event
    (``listener(event)``), it converts the event.
    """

    __slots__ = ("capture", "capture_many")

    def __init__(
        self,
        capture: Callable[[Capture], object],
        capture_many: Callable[[tuple[Capture, ...]], object] | None = None,
    ) -> None:
        self.capture = capture
        self.capture_many = capture_many or functools.partial(_each, capture)

    def __call__(self, event: Event) -> None:
        self.capture(event.capture())


def _each(capture: Callable[[Capture], object], captures: tuple[Capture, ...]) -> None:
    for one in captures:
        capture(one)


class EventBus:
    """The listeners of one tree of states (held by the tree's runtime context).

    ``listeners`` holds every listener as attached (it is true when anybody listens);
    ``event_listeners`` the ordinary ones and ``sinks`` the ``capture`` callables of the
    :class:`CaptureListener` ones.
    """

    __slots__ = (
        "_lock",
        "batch_sinks",
        "event_listeners",
        "listeners",
        "sinks",
    )

    def __init__(self) -> None:
        # Replaced, never mutated in place, so emitters iterate a stable list
        # without taking the lock.
        self.listeners: list[Listener] = []
        self.event_listeners: tuple[Listener, ...] = ()
        self.sinks: tuple[Callable[[Capture], object], ...] = ()
        self.batch_sinks: tuple[Callable[[tuple[Capture, ...]], object], ...] = ()
        self._lock = threading.Lock()

    def _set(self, listeners: list[Listener]) -> None:
        # sinks and event_listeners first: an emitter that sees a new ``listeners``
        # finds the lists that go with it.
        capturing = [lst for lst in listeners if isinstance(lst, CaptureListener)]
        self.sinks = tuple(lst.capture for lst in capturing)
        self.batch_sinks = tuple(lst.capture_many for lst in capturing)
        self.event_listeners = tuple(
            lst for lst in listeners if not isinstance(lst, CaptureListener)
        )
        self.listeners = listeners

    def add(self, listener: Listener) -> None:
        with self._lock:
            self._set([*self.listeners, listener])

    def remove(self, listener: Listener) -> None:
        with self._lock:
            # == and not `is`: each access to obj.method makes a new bound method.
            self._set([lst for lst in self.listeners if lst != listener])

    def __getstate__(self) -> dict[str, Any]:
        # Listeners watch a live run (files, sockets, viewers): a copy starts without.
        return {}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._set([])
        self._lock = threading.Lock()

    def emit(self, event: Event) -> None:
        """Deliver ``event`` to every listener (as a capture to the capture listeners).

        A listener that raises is removed (and reported once through
        ``smach.logerr``): watching must never break the robot's mission.
        """
        if self.sinks:
            self.capture(event.capture())
        if self.event_listeners:
            self.deliver(event)

    def deliver(self, event: Event) -> None:
        """Deliver ``event`` to the ordinary listeners only."""
        for listener in self.event_listeners:
            try:
                listener(event)
            except Exception as exc:
                self._detach(listener, exc)

    def capture(self, capture: Capture) -> None:
        """Deliver a capture to the capture listeners only.

        (The hottest emitters inline this loop; they call :meth:`sink_failed` the same way.)
        """
        for sink in self.sinks:
            try:
                sink(capture)
            except Exception as exc:
                self.sink_failed(sink, exc)

    def sink_failed(self, sink: Callable[[Any], object], exc: Exception) -> None:
        """Detach the capture listener whose ``capture`` (or ``capture_many``) raised."""
        owner = next(
            (
                lst
                for lst in self.listeners
                if isinstance(lst, CaptureListener) and sink in (lst.capture, lst.capture_many)
            ),
            None,
        )
        self._detach(owner if owner is not None else sink, exc)

    def _detach(self, listener: Any, exc: Exception) -> None:
        self.remove(listener)
        loggers.logerr(f"event listener {listener!r} raised {exc!r}; it was detached")
