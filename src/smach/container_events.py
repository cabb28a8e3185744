"""What a container reports while it runs: events, SMACH callbacks and INFO log lines.

:class:`ContainerEvents` is the part of :class:`~smach.container.Container` that talks
to watchers. Three audiences, each paid for only when present:

* capture listeners (journal, viewer) get plain tuples, ordinary listeners and the
  SMACH start/transition/termination callbacks get :class:`Event` objects; an event
  is built only when one of them is attached;
* INFO log lines (the original SMACH strings) are formatted only when a run found
  somebody who reads them (custom loggers installed, or the ``smach`` Python logger
  enabled for INFO; decided once per top-level run in ``Container._begin``). They do
  not go through events: a container with loggers and no listener builds no event.

Every ``_emit_*`` method does both: it sends the event to whoever listens and writes
the log line if lines are wanted. Callers test :meth:`ContainerEvents.is_observed`
first, so an unwatched run pays one attribute test per step.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

from smach.events import (
    Capture,
    ContainerStarted,
    ContainerTerminated,
    ErrorRaised,
    Event,
    Listener,
    StateEntered,
    StateExited,
    Transition,
    event_of,
)
from smach.log import loggers
from smach.runtime import Runtime
from smach.user_data import UserData

__all__ = ["ContainerEvents"]

_monotonic = time.monotonic
_current_thread = threading.current_thread

_Callbacks = tuple[tuple[Callable[..., Any], tuple[Any, ...]], ...]


class ContainerEvents:
    """Events, callbacks and log lines of a container (mixed into ``Container``)."""

    #: Which of this container's own events trigger the SMACH transition callbacks.
    _transition_cb_events: ClassVar[tuple[type[Event], ...]] = (Transition,)

    _rt: Runtime
    _path: str
    _userdata: UserData
    # The SMACH callbacks, registered (rarely) on the instance. Empty class-level
    # defaults keep a container's instance attributes at most 29: CPython (3.11+)
    # stores up to 29 attributes shared-key and inline; a 30th turns every instance's
    # attributes into its own dict, which costs a fresh machine's first run about
    # twice the memory reads (see docs/performance.md, smach core).
    _start_cbs: _Callbacks = ()
    _transition_cbs: _Callbacks = ()
    _termination_cbs: _Callbacks = ()
    # Listeners of this container's own events only (the SMACH callbacks).
    _local: tuple[Listener, ...]
    # Whether this run writes INFO log lines (see Container._begin).
    _log_info: bool
    # The thread running this container, when somebody listens (see _announce_start).
    _thread: str | None
    #: Whether this class writes a line when a child is entered (``_log_entered``
    #: overridden): set per class, so a loop tests one flag.
    _logs_entries: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._logs_entries = cls._log_entered is not ContainerEvents._log_entered

    def get_initial_states(self) -> list[str]:
        raise NotImplementedError

    def get_active_states(self) -> list[str]:
        raise NotImplementedError

    def _start_states(self) -> list[str]:
        raise NotImplementedError

    def _terminal_states(self) -> list[str]:
        raise NotImplementedError

    # -- listeners and callbacks ------------------------------------------------------------
    def add_listener(self, listener: Listener) -> None:
        """Receive every event of the whole tree this container belongs to."""
        self._rt.bus.add(listener)

    def remove_listener(self, listener: Listener) -> None:
        self._rt.bus.remove(listener)

    def register_start_cb(self, start_cb: Callable[..., Any], cb_args: Sequence[Any] = ()) -> None:
        """``start_cb(userdata, initial_states, *cb_args)`` at the start of each run."""
        self._start_cbs = (*self._start_cbs, (start_cb, tuple(cb_args)))
        self._refresh_local()

    def register_transition_cb(
        self, transition_cb: Callable[..., Any], cb_args: Sequence[Any] = ()
    ) -> None:
        """``transition_cb(userdata, active_states, *cb_args)`` after each transition."""
        self._transition_cbs = (*self._transition_cbs, (transition_cb, tuple(cb_args)))
        self._refresh_local()

    def register_termination_cb(
        self, termination_cb: Callable[..., Any], cb_args: Sequence[Any] = ()
    ) -> None:
        """``termination_cb(userdata, terminal_states, outcome, *cb_args)`` at the end."""
        self._termination_cbs = (*self._termination_cbs, (termination_cb, tuple(cb_args)))
        self._refresh_local()

    def call_start_cbs(self) -> None:
        self._call_cbs("start", self._start_cbs, (self._userdata, self.get_initial_states()))

    def call_transition_cbs(self) -> None:
        self._call_cbs(
            "transition", self._transition_cbs, (self._userdata, self.get_active_states())
        )

    def call_termination_cbs(self, terminal_states: Sequence[str], outcome: str | None) -> None:
        self._call_cbs(
            "termination", self._termination_cbs, (self._userdata, list(terminal_states), outcome)
        )

    def _call_cbs(self, kind: str, cbs: _Callbacks, args: tuple[Any, ...]) -> None:
        # Callbacks observe; a failing observer (say, an introspection publisher) must
        # not abort the robot's task. The error is logged with where it came from, and
        # the remaining callbacks still run.
        for cb, extra in cbs:
            try:
                cb(*args, *extra)
            except Exception as exc:
                loggers.logerr(
                    f"{self._path}: {kind} callback {getattr(cb, '__qualname__', cb)!r} raised "
                    f"{type(exc).__name__}: {exc}"
                )

    def _callbacks_listener(self, event: Event) -> None:
        if isinstance(event, ContainerStarted):
            self._call_cbs("start", self._start_cbs, (self._userdata, list(event.initial_states)))
        elif isinstance(event, self._transition_cb_events):
            self.call_transition_cbs()
        elif isinstance(event, ContainerTerminated):
            self.call_termination_cbs(event.terminal_states, event.outcome)

    def _refresh_local(self) -> None:
        has_cbs = self._start_cbs or self._transition_cbs or self._termination_cbs
        self._local = (self._callbacks_listener,) if has_cbs else ()

    # -- INFO log lines (override per container type; called only when lines are wanted) --
    # The start and termination lines take what they show from the container (one call
    # per line: this runs once per container run whenever loggers are installed).
    def _log_started(self) -> None:
        loggers.loginfo(f"{type(self).__name__} {self._path} starting in {self._start_states()}")

    def _log_entered(self, label: str) -> None:
        """No line by default (the original SMACH wrote none)."""

    def _log_exited(self, label: str, outcome: str | None) -> None:
        """No line by default (the original SMACH wrote none)."""

    def _log_transition(self, source: str, outcome: str, target: str) -> None:
        loggers.loginfo(
            f"{type(self).__name__} {self._path} transitioning '{source}':'{outcome}'-->'{target}'"
        )

    def _log_terminated(self, outcome: str | None) -> None:
        loggers.loginfo(
            f"{type(self).__name__} {self._path} terminating "
            f"{self._terminal_states()} with outcome '{outcome}'"
        )

    # -- emitting --------------------------------------------------------------------------
    def is_observed(self) -> bool:
        """Whether anybody listens to this container's events or reads its log lines
        (extension API: test it before building an event of your own)."""
        return bool(self._rt.bus.listeners or self._local or self._log_info)

    def emit_event(self, event: Event) -> None:
        """Send an event to the tree's listeners and this container's local ones
        (extension API: a container's own event types, any :class:`smach.events.Event`
        subclass, reach the journal, the viewer and ``add_listener`` callbacks)."""
        if self._rt.bus.listeners:
            self._rt.bus.emit(event)
        for listener in self._local:
            listener(event)

    def _deliver(self, event: Event) -> None:
        """Send an event the capture listeners already got to everybody else."""
        if self._rt.bus.event_listeners:
            self._rt.bus.deliver(event)
        for listener in self._local:
            listener(event)

    def _send(self, cls: type[Event], path: str, thread: str | None, *fields: Any) -> None:
        """Send an event to the listeners: a tuple to the capture listeners (journal,
        viewer), an Event object only if somebody else listens. ``thread`` may be given
        by a caller that knows it (a run's own thread)."""
        capture = (cls, path, _monotonic(), thread or _current_thread().name, *fields)
        bus = self._rt.bus
        if bus.sinks:
            bus.capture(capture)
        if bus.event_listeners or self._local:
            self._deliver(event_of(capture))

    def _release(self, pending: tuple[Capture, ...]) -> tuple[Capture, ...]:
        """Send held captures to the capture listeners in one call; return ``()``."""
        if pending:
            bus = self._rt.bus
            for sink in bus.batch_sinks:
                try:
                    sink(pending)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        return ()

    def _report_entered(
        self, label: str, path: str, thread: str | None, pending: tuple[Capture, ...]
    ) -> None:
        """``state_entered`` of the child at ``path`` (after ``pending``), or its log line."""
        bus = self._rt.bus
        if bus.event_listeners or self._local:
            self._release(pending)
            self._emit_entered(label, thread)  # (and the log line, if wanted)
            return
        if bus.sinks:  # capture listeners only (journal, viewer): no Event object
            capture = (StateEntered, path, _monotonic(), thread or _current_thread().name, label)
            if pending:
                self._release((*pending, capture))
            else:
                bus.capture(capture)
        else:
            self._release(pending)
        if self._log_info:
            self._log_entered(label)

    # Each emitter: the event if anybody listens, the log line if lines are wanted.
    def _emit_started(self, initial_states: Sequence[str], thread: str | None = None) -> None:
        if self._rt.bus.listeners or self._local:
            kind = type(self).__name__
            self._send(ContainerStarted, self._path, thread, kind, tuple(initial_states))
        if self._log_info:
            self._log_started()

    def _announce_start(self) -> None:
        """A run starts: the start event when somebody listens (the running thread's
        name, read once, goes with every event of the run's own loop), else the start
        line if lines are wanted."""
        if self._rt.bus.listeners or self._local:
            self._thread = _current_thread().name
            self._emit_started(self._start_states(), self._thread)
        else:
            self._thread = None
            if self._log_info:
                self._log_started()

    def _emit_entered(self, label: str, thread: str | None = None) -> None:
        if self._rt.bus.listeners or self._local:
            self._send(StateEntered, f"{self._path}/{label}", thread, label)
        if self._log_info:
            self._log_entered(label)

    def _emit_exited(self, label: str, outcome: str | None, thread: str | None = None) -> None:
        if self._rt.bus.listeners or self._local:
            self._send(StateExited, f"{self._path}/{label}", thread, label, outcome)
        if self._log_info:
            self._log_exited(label, outcome)

    def report_transition(
        self, source: str, outcome: str, target: str, thread: str | None = None
    ) -> None:
        """Report a transition between children (extension API: for containers that
        have transitions; the SMACH transition callbacks and the log line follow it)."""
        if self._rt.bus.listeners or self._local:
            self._send(Transition, self._path, thread, source, outcome, target)
        if self._log_info:
            self._log_transition(source, outcome, target)

    _emit_transition = report_transition  # (its name before the extension API was public)

    def _emit_terminated(
        self, terminal_states: Sequence[str], outcome: str | None, thread: str | None = None
    ) -> None:
        if self._rt.bus.listeners or self._local:
            states = tuple(terminal_states)
            self._send(ContainerTerminated, self._path, thread, states, outcome)
        if self._log_info:
            self._log_terminated(outcome)

    def _emit_error(self, exc: BaseException) -> None:
        if self._rt.bus.listeners:
            self._send(ErrorRaised, self._path, None, type(exc).__name__, str(exc))
