"""Small states and thread helpers for the smach core tests."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable
from typing import Any

import smach

#: Upper bound for anything that should happen "at once"; only used to detect hangs.
HANG = 5.0


class Leaf(smach.State):
    """Returns ``result`` (default: its first outcome) and counts its executions."""

    def __init__(
        self,
        outcomes: Iterable[str] = ("done",),
        result: str | None = None,
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        io_keys: Iterable[str] = (),
    ) -> None:
        outcomes = list(outcomes)
        super().__init__(outcomes, list(input_keys), list(output_keys), list(io_keys))
        self.result = outcomes[0] if result is None else result
        self.calls = 0

    def execute(self, ud: Any) -> str | None:
        self.calls += 1
        return self.result


class Fn(smach.State):
    """Calls ``fn(self, ud)`` and returns what it returns."""

    def __init__(
        self,
        fn: Callable[[Fn, Any], Any],
        outcomes: Iterable[str] = ("done",),
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        io_keys: Iterable[str] = (),
    ) -> None:
        super().__init__(list(outcomes), list(input_keys), list(output_keys), list(io_keys))
        self.fn = fn
        self.calls = 0

    def execute(self, ud: Any) -> Any:
        self.calls += 1
        return self.fn(self, ud)


class Blocker(smach.State):
    """Signals ``started``, then blocks on ``preempt_event``.

    Returns ``'preempted'`` (after servicing) when preempted, ``'timeout'`` if nobody
    preempted it within ``HANG`` seconds (a lost preempt).
    """

    def __init__(self, outcomes: Iterable[str] = ("preempted", "timeout")) -> None:
        super().__init__(list(outcomes))
        self.started = threading.Event()
        self.saw_preempt = False
        self.calls = 0

    def execute(self, ud: Any) -> str:
        self.calls += 1
        self.started.set()
        if self.preempt_event.wait(HANG):
            self.saw_preempt = True
            self.service_preempt()
            return "preempted"
        return "timeout"


class PreemptAtStart(smach.State):
    """Returns ``'preempted'`` (serviced) if a preempt is pending when it starts."""

    def __init__(self, outcomes: Iterable[str] = ("done", "preempted")) -> None:
        super().__init__(list(outcomes))
        self.calls = 0
        self.saw_preempt = False

    def execute(self, ud: Any) -> str:
        self.calls += 1
        if self.preempt_requested():
            self.saw_preempt = True
            self.service_preempt()
            return "preempted"
        return "done"


def start_thread(fn: Callable[[], object]) -> threading.Thread:
    thread = threading.Thread(target=fn, daemon=True)
    thread.start()
    return thread


def preempt_when(event: threading.Event, target: smach.State) -> threading.Thread:
    """A thread that waits for ``event`` and then preempts ``target``."""

    def run() -> None:
        if event.wait(HANG):
            target.request_preempt()

    return start_thread(run)


def join(*threads: threading.Thread) -> None:
    for thread in threads:
        thread.join(HANG)
        assert not thread.is_alive(), f"thread {thread.name} did not finish"


def all_flags(state: smach.State) -> dict[str, bool]:
    """``{path or repr: preempt_requested()}`` for a state and every descendant."""
    flags = {state.path or repr(state): state.preempt_requested()}
    if isinstance(state, smach.Container):
        for child in state.get_children().values():
            flags.update(all_flags(child))
    return flags


class LogRecorder:
    """Four recording loggers, installed with smach.set_loggers."""

    def __init__(self) -> None:
        self.info: list[str] = []
        self.warn: list[str] = []
        self.debug: list[str] = []
        self.error: list[str] = []

    def install(self) -> None:
        smach.set_loggers(self.info.append, self.warn.append, self.debug.append, self.error.append)


class Runner:
    """Runs ``root.execute(ud)`` in a thread; ``result()`` joins with a timeout and
    re-raises what the run raised."""

    def __init__(self, root: smach.State, ud: smach.UserData | None = None) -> None:
        self.outcome: list[str | None] = []
        self.errors: list[BaseException] = []

        def run() -> None:
            try:
                self.outcome.append(root.execute(ud))  # type: ignore[arg-type]
            except BaseException as exc:
                self.errors.append(exc)

        self.thread = threading.Thread(target=run, name="runner", daemon=True)
        self.thread.start()

    def result(self, timeout: float = 10.0) -> str | None:
        self.thread.join(timeout)
        assert not self.thread.is_alive(), "the run did not finish"
        if self.errors:
            raise self.errors[0]
        return self.outcome[0]
