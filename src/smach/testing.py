"""Fakes for testing state machines: scripted states, blocking states, event recorders.

These are meant for users' tests as much as for smach's own::

    pick = ScriptedState(["aborted", "succeeded"])   # fails once, then succeeds
    sm = ...  # build a machine around it
    assert sm.execute() == "done" and pick.call_count == 2
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from smach.events import Event
from smach.exceptions import InvalidStateError
from smach.state import State
from smach.user_data import UserData

__all__ = ["BlockingState", "Call", "EventRecorder", "RaisingState", "ScriptedState"]


@dataclass(frozen=True)
class Call:
    """One execution of a fake state."""

    inputs: dict[str, Any]
    thread: str
    time: float
    preempt_requested: bool


class ScriptedState(State):
    """Returns the scripted outcomes in order (the last one repeats).

    Records every call (inputs read, thread, time). ``writes`` maps output keys to
    values written on every call. ``delay`` sleeps (preempt-aware) before returning;
    if preempted during the delay the state returns ``'preempted'`` when that is one
    of its outcomes.
    """

    def __init__(
        self,
        script: Sequence[str],
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        writes: Mapping[str, Any] | None = None,
        delay: float = 0.0,
    ) -> None:
        if isinstance(script, str) or not script:
            raise InvalidStateError("ScriptedState needs a non-empty list of outcomes")
        names = list(outcomes) if outcomes is not None else list(dict.fromkeys(script))
        writes = dict(writes or {})
        keys = list(output_keys) if output_keys is not None else []
        super().__init__(names, input_keys, [*keys, *(k for k in writes if k not in keys)])
        self.script = list(script)
        self.writes = writes
        self.delay = delay
        self.calls: list[Call] = []

    @property
    def call_count(self) -> int:
        return len(self.calls)

    def execute(self, ud: UserData) -> str | None:
        inputs = {k: ud[k] for k in self.get_registered_input_keys() if k in ud}
        self.calls.append(
            Call(
                inputs, threading.current_thread().name, time.monotonic(), self.preempt_requested()
            )
        )
        if self.delay and self.sleep(self.delay) and "preempted" in self._outcomes:
            self.service_preempt()
            return "preempted"
        for key, value in self.writes.items():
            ud[key] = value
        return self.script[min(len(self.calls), len(self.script)) - 1]


class BlockingState(State):
    """Blocks until preempted (returns ``'preempted'``) or released with an outcome.

    ``started`` is set when execute begins, so a test can wait for the state to be
    running before it preempts or releases it. ``timeout`` bounds the wait so a test
    never hangs; when it expires the state returns ``timeout_outcome``.
    """

    def __init__(
        self,
        outcomes: Iterable[str] = ("done", "preempted"),
        timeout: float = 30.0,
        timeout_outcome: str | None = None,
        service: bool = True,
    ) -> None:
        super().__init__(outcomes)
        self.started = threading.Event()
        self.timeout = timeout
        self.timeout_outcome = timeout_outcome or next(iter(self._outcomes))
        self.service = service
        self._release: str | None = None
        self._wake = threading.Condition()
        self.executions = 0

    def release(self, outcome: str) -> None:
        """Make the running (or next) execution return ``outcome``."""
        with self._wake:
            self._release = outcome
            self._wake.notify_all()

    def request_preempt(self) -> None:
        super().request_preempt()
        with self._wake:
            self._wake.notify_all()

    def execute(self, ud: UserData) -> str | None:
        self.executions += 1
        self.started.set()
        deadline = time.monotonic() + self.timeout
        with self._wake:
            while True:
                if self._release is not None:
                    outcome, self._release = self._release, None
                    return outcome
                if self.preempt_requested():
                    if self.service:
                        self.service_preempt()
                    return "preempted"
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return self.timeout_outcome
                self._wake.wait(remaining)


class RaisingState(State):
    """Raises ``error`` (an exception instance or a factory) when executed."""

    def __init__(
        self,
        error: BaseException | Callable[[], BaseException] | None = None,
        outcomes: Iterable[str] = ("done",),
    ) -> None:
        super().__init__(outcomes)
        self.error = error if error is not None else RuntimeError("boom")

    def execute(self, ud: UserData) -> str | None:
        raise self.error if isinstance(self.error, BaseException) else self.error()


class EventRecorder:
    """A listener that keeps every event; attach with ``container.add_listener(rec)``."""

    def __init__(self) -> None:
        self.events: list[Event] = []
        self._cond = threading.Condition()

    def __call__(self, event: Event) -> None:
        with self._cond:
            self.events.append(event)
            self._cond.notify_all()

    def kinds(self) -> list[str]:
        return [e.kind for e in list(self.events)]

    def of_kind(self, kind: str) -> list[Event]:
        return [e for e in list(self.events) if e.kind == kind]

    def wait_for(self, predicate: Callable[[Event], bool], timeout: float = 5.0) -> Event:
        """Block until an event matching ``predicate`` was recorded; raise on timeout."""
        deadline = time.monotonic() + timeout
        seen = 0
        with self._cond:
            while True:
                for event in self.events[seen:]:
                    if predicate(event):
                        return event
                seen = len(self.events)
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise TimeoutError(f"no matching event within {timeout} s")
                self._cond.wait(remaining)
