"""Runtime control of a running tree: pause, resume, step, breakpoints, preempt, force.

One :class:`Controller` per tree of states, attached with ``Controller(root)``. The
Python API, the CLI, the web viewer and the ROS 2 services all call the same
methods, and every call is recorded (what, from where, when) and reported to the
controller's observers (the journal writes them as ``control`` records).

Semantics (docs/control.md has the guarantees):

* **pause** takes effect at the next transition: a running state is not
  interrupted, and no container starts a new state while paused. In a
  ``Concurrence`` every branch holds at its own next transition.
* **resume** lets every held state start; **step** lets exactly one held (or the
  next) state start, then the tree is paused again.
* **breakpoints** are state paths or ``fnmatch`` patterns (``/ROOT/*/PICK``); a
  state whose path matches is held *before* it is entered and the tree pauses.
* **preempt** is the ordinary cooperative preemption; a held state is released
  by it (it starts with the request pending and normally returns at once).
* **force_outcome** preempts a running state (the active leaf by default) and,
  when it returns, its container takes the given outcome instead of the one it
  returned. The outcome must be one of the state's outcomes.

The containers call two hooks, :meth:`Controller.enter` before a child starts and
:meth:`Controller.leave` after it returns, only when a controller is attached to
their tree (``Runtime.control``: the controller is the tree's step hook). A controller also attaches a no-op capture
listener, so a controlled tree is an observed one: the ``StateMachine`` loop looks
for a controller only on the steps somebody observes, and an unobserved machine
pays one test of a local variable per transition for control.

Locking: one re-entrant lock guards the controller's state; it is held while a
state's ``request_preempt`` runs (so that a forced outcome is registered and the
state preempted atomically with respect to the state returning), and
``State.request_preempt`` wakes held states through :meth:`Controller.wake`, hence
re-entrant. Observers are called after the lock is released.
"""

from __future__ import annotations

import fnmatch
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from smach.container import Container
from smach.events import CaptureListener
from smach.exceptions import SmachError
from smach.log import loggers
from smach.state import State

__all__ = [
    "CONTROL_STATES",
    "ControlError",
    "ControlRecord",
    "ControlStatus",
    "Controller",
    "controller_of",
]

ControlState = Literal["running", "pausing", "paused", "at_breakpoint"]

#: The documented states of a controller (see :attr:`ControlStatus.state`).
CONTROL_STATES: tuple[ControlState, ...] = ("running", "pausing", "paused", "at_breakpoint")

#: How many control records a controller keeps in :attr:`Controller.history`.
HISTORY = 1000

_MAX_PATTERN = 500
_MAX_SOURCE = 100


class ControlError(SmachError):
    """A control request that cannot be carried out (what, where, what is allowed)."""


@dataclass(frozen=True)
class ControlStatus:
    """What the controller is doing, as one immutable value.

    ``state`` is one of :data:`CONTROL_STATES`:

    * ``running``: not paused;
    * ``pausing``: paused, but no state is held yet (running states finish first);
    * ``paused``: at least one state is held before it starts (``held``);
    * ``at_breakpoint``: paused because ``breakpoint`` (a state path) matched one
      of ``breakpoints``; it stays so until ``resume`` or ``step``.
    """

    state: ControlState
    held: tuple[str, ...] = ()
    """Paths of the states held before they start, oldest first."""
    breakpoint: str | None = None
    breakpoints: tuple[str, ...] = ()
    running: tuple[str, ...] = ()
    """Paths of the states started under this controller that have not returned."""
    steps: int = 0
    """Steps granted and not used yet."""
    forced: Mapping[str, str] = field(default_factory=dict)
    """Path -> outcome of forced outcomes waiting for their state to return."""

    def describe(self) -> str:
        """One line for people: ``at breakpoint /ROOT/PICK``, ``paused before /ROOT/B``."""
        if self.state == "at_breakpoint":
            return f"at breakpoint {self.breakpoint}"
        if self.state == "paused":
            return "paused before " + ", ".join(self.held)
        if self.state == "pausing":
            waiting = ", ".join(self.running) or "the running states"
            return f"pausing (waiting for {waiting} to return)"
        return "running"

    def to_json(self) -> dict[str, Any]:
        return {
            "state": self.state,
            "describe": self.describe(),
            "held": list(self.held),
            "breakpoint": self.breakpoint,
            "breakpoints": list(self.breakpoints),
            "running": list(self.running),
            "steps": self.steps,
            "forced": dict(self.forced),
        }


@dataclass(frozen=True)
class ControlRecord:
    """One control action: what, from where, when, and the state it left.

    ``time`` is ``time.monotonic()`` (the clock of the events, so a replay can place
    the record among them) and ``wall`` is ``time.time()``. ``source`` says where
    the request came from (``api``, ``cli``, ``viewer``, ``ros``, or ``machine``
    for what the tree did by itself: a breakpoint hit, a forced outcome taken).
    """

    action: str
    source: str
    time: float
    wall: float
    thread: str
    path: str = ""
    details: Mapping[str, Any] = field(default_factory=dict)
    state: str = "running"

    def to_json(self) -> dict[str, Any]:
        return {
            "action": self.action,
            "source": self.source,
            "time": self.time,
            "wall": self.wall,
            "thread": self.thread,
            "path": self.path,
            "details": dict(self.details),
            "state": self.state,
        }


Observer = Callable[[ControlRecord], object]


def _ignore(capture: object) -> None:
    """The controller's listener: it only makes the tree observed (see Controller)."""


def controller_of(state: State) -> Controller | None:
    """The controller attached to the tree ``state`` belongs to, if any."""
    control = state._rt.control
    return control if isinstance(control, Controller) else None


def check_pattern(pattern: object) -> str:
    """Return ``pattern`` if it is a usable breakpoint, else raise :class:`ControlError`."""
    if not isinstance(pattern, str) or not pattern.strip():
        raise ControlError(f"a breakpoint must be a non-empty string, got {pattern!r}")
    if len(pattern) > _MAX_PATTERN:
        raise ControlError(f"a breakpoint is at most {_MAX_PATTERN} characters long")
    if not pattern.startswith(("/", "*")):
        raise ControlError(
            f"breakpoint {pattern!r} is neither a state path nor a pattern: use a path "
            f"like /ROOT/PICK or a glob like */PICK or /ROOT/*/PICK"
        )
    return pattern


class _Waiter:
    __slots__ = ("path",)

    def __init__(self, path: str) -> None:
        self.path = path


class Controller:
    """Pause, resume, step, breakpoints, preempt and forced outcomes for one tree.

    ``Controller(root)`` attaches to the tree of ``root`` (one controller per tree);
    :meth:`close` (or leaving a ``with`` block) detaches it and lets held states go.
    All methods may be called from any thread, at any time, also before or between
    runs (a tree paused before ``execute`` holds its first state).
    """

    def __init__(self, root: Container) -> None:
        if not isinstance(root, Container):
            raise ControlError(
                f"Controller needs a smach container (the root of the tree to control), "
                f"got {type(root).__name__}"
            )
        rt = root._rt
        if rt.control is not None:
            raise ControlError(f"{root.path or 'the tree'} already has a controller attached")
        self.root = root
        self._lock = threading.RLock()
        self._cond = threading.Condition(self._lock)
        self._paused = False
        self._breakpoint: str | None = None
        self._breakpoints: dict[str, None] = {}
        self._steps = 0
        self._held: dict[_Waiter, None] = {}
        self._running: dict[str, State] = {}
        self._forced: dict[str, str] = {}
        self._closed = False
        self._observers: tuple[Observer, ...] = ()
        self.history: deque[ControlRecord] = deque(maxlen=HISTORY)
        # A controlled tree is an observed tree: the StateMachine loop looks for the
        # controller only on steps somebody observes, so an unobserved machine pays
        # nothing for control. This capture listener ignores what it gets.
        self._marker = CaptureListener(_ignore, _ignore)
        rt.control = self
        rt.bus.add(self._marker)

    # -- life cycle ------------------------------------------------------------------------
    def close(self) -> None:
        """Detach from the tree; held states start (as after ``resume``)."""
        with self._cond:
            self._closed = True
            self._paused = False
            self._breakpoint = None
            self._steps = 0
            self._cond.notify_all()
        rt = self.root._rt
        if rt.control is self:
            rt.control = None
        rt.bus.remove(self._marker)

    def __enter__(self) -> Controller:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def add_observer(self, observer: Observer) -> None:
        """Call ``observer(record)`` for every :class:`ControlRecord` from now on."""
        with self._lock:
            self._observers = (*self._observers, observer)

    def journal_to(self, journal: Any) -> Observer:
        """Write every control action to ``journal`` as a ``control`` record from now on.

        ``journal`` is a :class:`smach.introspection.journal.Journal` (anything with its
        ``write_record(kind, **fields)``); the record is on disk when the request
        returns. Returns the observer (for :meth:`remove_observer`).
        """

        def write(record: ControlRecord) -> None:
            journal.write_record("control", **record.to_json())

        self.add_observer(write)
        return write

    def remove_observer(self, observer: Observer) -> None:
        with self._lock:
            self._observers = tuple(o for o in self._observers if o != observer)

    # -- requests ---------------------------------------------------------------------------
    def pause(self, *, source: str = "api") -> ControlStatus:
        """Hold every container at its next transition (running states go on)."""
        with self._cond:
            self._paused = True
            self._cond.notify_all()
            record = self._record("pause", source)
        return self._done(record)

    def resume(self, *, source: str = "api") -> ControlStatus:
        """Let every held state start; forget unused steps and the breakpoint hit."""
        with self._cond:
            self._paused = False
            self._breakpoint = None
            self._steps = 0
            self._cond.notify_all()
            record = self._record("resume", source)
        return self._done(record)

    def step(self, *, source: str = "api") -> ControlStatus:
        """Let one state start (the longest held, or the next to come), then pause.

        Called while running, it pauses the tree after the next state has started.
        """
        with self._cond:
            self._paused = True
            self._breakpoint = None
            self._steps += 1
            self._cond.notify_all()
            record = self._record("step", source)
        return self._done(record)

    def add_breakpoint(self, pattern: str, *, source: str = "api") -> ControlStatus:
        """Hold (and pause) before entering any state whose path matches ``pattern``.

        ``pattern`` is a path (``/ROOT/FETCH/PICK``) or an ``fnmatch`` glob, where
        ``*`` also matches ``/`` (``*/PICK`` is every state labelled PICK).
        """
        pattern = check_pattern(pattern)
        with self._cond:
            self._breakpoints[pattern] = None
            record = self._record("add_breakpoint", source, pattern)
        return self._done(record)

    def remove_breakpoint(self, pattern: str, *, source: str = "api") -> ControlStatus:
        """Remove a breakpoint set with :meth:`add_breakpoint` (the same text)."""
        with self._cond:
            if pattern not in self._breakpoints:
                raise ControlError(
                    f"no breakpoint {pattern!r}; breakpoints: "
                    f"{', '.join(self._breakpoints) or 'none'}"
                )
            del self._breakpoints[pattern]
            record = self._record("remove_breakpoint", source, pattern)
        return self._done(record)

    def toggle_breakpoint(self, pattern: str, *, source: str = "api") -> ControlStatus:
        """Add the breakpoint if it is not set, else remove it."""
        with self._lock:
            present = pattern in self._breakpoints
        if present:
            return self.remove_breakpoint(pattern, source=source)
        return self.add_breakpoint(pattern, source=source)

    def clear_breakpoints(self, *, source: str = "api") -> ControlStatus:
        with self._cond:
            self._breakpoints.clear()
            record = self._record("clear_breakpoints", source)
        return self._done(record)

    def preempt(self, path: str | None = None, *, source: str = "api") -> ControlStatus:
        """Request preemption of the root (or of the state at ``path``).

        A held state is released by the request (it starts with it pending).
        """
        with self._cond:
            target = self.root if path is None else self.find(path)
            record = self._record("preempt", source, target.path)
        target.request_preempt()
        self.wake()
        return self._done(record)

    def force_outcome(
        self, outcome: str, path: str | None = None, *, source: str = "api"
    ) -> ControlStatus:
        """Preempt a running state and make its container take ``outcome`` from it.

        ``path`` defaults to the active leaf (the one running state that is not a
        container). Raises :class:`ControlError` when nothing (or more than one leaf)
        is running, ``path`` is not running (it may just have returned), or
        ``outcome`` is not one of the state's outcomes.
        """
        with self._cond:
            if path is None:
                leaves = [p for p, s in self._running.items() if not isinstance(s, Container)]
                if not leaves:
                    raise ControlError(
                        "force_outcome: no state is running under this controller"
                        + self._held_note()
                    )
                if len(leaves) > 1:
                    raise ControlError(
                        f"force_outcome: {len(leaves)} states are running "
                        f"({', '.join(leaves)}); name one with path="
                    )
                path = leaves[0]
            state = self._running.get(path)
            if state is None:
                running = ", ".join(self._running) or "none"
                raise ControlError(
                    f"force_outcome: {path} is not running (it may just have returned); "
                    f"running: {running}" + self._held_note()
                )
            allowed = state.get_registered_outcomes()
            if outcome not in allowed:
                raise ControlError(
                    f"force_outcome: {path} has no outcome {outcome!r}; its outcomes: "
                    f"{', '.join(allowed) or 'none'}"
                )
            self._forced[path] = outcome
            # Under the lock: leave() cannot take the state's return in between.
            state.request_preempt()
            record = self._record("force_outcome", source, path, outcome=outcome)
        return self._done(record)

    def note(
        self, action: str, *, source: str = "api", path: str = "", **details: Any
    ) -> ControlRecord:
        """Record a control action carried out elsewhere (a mission's skip, replan, goal).

        It joins this controller's :attr:`history` and goes to its observers (the
        journal), so every control action of a tree is in one stream.
        """
        with self._lock:
            record = self._record(action, source, path, **details)
        self._notify([record])
        return record

    # -- reading ---------------------------------------------------------------------------
    def status(self) -> ControlStatus:
        with self._lock:
            return self._status()

    @property
    def breakpoints(self) -> tuple[str, ...]:
        with self._lock:
            return tuple(self._breakpoints)

    def matches(self, path: str) -> str | None:
        """The first breakpoint matching ``path`` (None if none does)."""
        with self._lock:
            return self._match(path)

    def wait_for(self, state: ControlState | Iterable[ControlState], timeout: float) -> bool:
        """Wait until the controller is in ``state`` (or one of them); False on timeout."""
        wanted = {state} if isinstance(state, str) else set(state)
        unknown = wanted - set(CONTROL_STATES)
        if unknown:
            raise ControlError(
                f"unknown control state(s) {sorted(unknown)}; states: {', '.join(CONTROL_STATES)}"
            )
        with self._cond:
            return self._cond.wait_for(lambda: self._status().state in wanted, timeout)

    def wake(self) -> None:
        """Make held states look at their preempt flags again (``request_preempt`` calls it)."""
        with self._cond:
            self._cond.notify_all()

    # -- the containers' hooks ---------------------------------------------------------------
    def enter(self, container: State, path: str, state: State) -> None:
        """Called by ``container`` before it starts ``state`` (at ``path``); may block."""
        # The lock itself (C), not the Condition's Python-level __enter__: this runs on
        # every step of a controlled tree. It is the Condition's lock.
        with self._lock:
            self._forced.pop(path, None)  # a force that missed an earlier run of this path
            if self._closed or not (self._paused or self._breakpoints):
                self._running[path] = state
                return
            hit: ControlRecord | None = None
            pattern = self._match(path) if self._breakpoints else None
            if pattern is not None:
                self._paused = True
                self._breakpoint = path
                self._cond.notify_all()
                hit = self._record("breakpoint_hit", "machine", path, pattern=pattern)
        if hit is not None:
            self._notify([hit])
        with self._cond:
            self._hold(container, path, state)
            self._running[path] = state

    def leave(self, path: str, state: State, outcome: str | None) -> str | None:
        """Called by the container after ``state`` returned ``outcome``; returns the outcome to take."""
        with self._lock:
            self._running.pop(path, None)
            forced = self._forced.pop(path, None)
            if forced is None:
                return outcome
            # The preempt was only the means of the forced outcome: it must not flow on.
            if state._preempt_requested:
                state.recall_preempt()
            record = self._record(
                "outcome_forced", "machine", path, outcome=forced, returned=outcome
            )
        self._done(record)
        return forced

    # -- internals ---------------------------------------------------------------------------
    def _hold(self, container: State, path: str, state: State) -> None:
        waiter = _Waiter(path)
        held = self._held
        held[waiter] = None
        self._cond.notify_all()  # wait_for() callers: the state changed
        try:
            while self._paused and not self._closed:
                if container._preempt_requested or state._preempt_requested:
                    return
                if self._steps > 0 and next(iter(held)) is waiter:
                    self._steps -= 1
                    return
                self._cond.wait()
        finally:
            del held[waiter]
            self._cond.notify_all()  # the next held state may have a step to use

    def _match(self, path: str) -> str | None:
        for pattern in self._breakpoints:
            if path == pattern or fnmatch.fnmatchcase(path, pattern):
                return pattern
        return None

    def find(self, path: str) -> State:
        """The state at ``path`` in this tree (ControlError naming the children if none)."""
        if not isinstance(path, str) or not path.startswith("/"):
            raise ControlError(f"a state path starts with '/', got {path!r}")
        node: State = self.root
        root = self.root.path
        if path == root:
            return node
        if not path.startswith(root + "/"):
            raise ControlError(f"{path} is not in this tree; its root is {root}")
        for label in path[len(root) + 1 :].split("/"):
            children = node.get_children() if isinstance(node, Container) else {}
            if label not in children:
                raise ControlError(
                    f"{path}: {node.path} has no child {label!r}; children: "
                    f"{', '.join(children) or 'none'}"
                )
            node = children[label]
        return node

    def _held_note(self) -> str:
        held = [w.path for w in self._held]
        return f"; held before starting: {', '.join(held)}" if held else ""

    def _status(self) -> ControlStatus:
        held = tuple(w.path for w in self._held)
        state: ControlState
        if not self._paused:
            state = "running"
        elif self._breakpoint is not None:
            state = "at_breakpoint"
        elif held:
            state = "paused"
        else:
            state = "pausing"
        return ControlStatus(
            state=state,
            held=held,
            breakpoint=self._breakpoint,
            breakpoints=tuple(self._breakpoints),
            running=tuple(self._running),
            steps=self._steps,
            forced=dict(self._forced),
        )

    def _record(self, action: str, source: str, path: str = "", **details: Any) -> ControlRecord:
        if not isinstance(source, str) or not source or len(source) > _MAX_SOURCE:
            raise ControlError(
                f"a control source is a short non-empty string (api, cli, viewer, ros), "
                f"got {source!r}"
            )
        record = ControlRecord(
            action=action,
            source=source,
            time=time.monotonic(),
            wall=time.time(),
            thread=threading.current_thread().name,
            path=path,
            details=details,
            state=self._status().state,
        )
        self.history.append(record)
        return record

    def _done(self, record: ControlRecord) -> ControlStatus:
        """Tell the observers (outside the lock); return the status now."""
        self._notify([record])
        return self.status()

    def _notify(self, records: list[ControlRecord]) -> None:
        for record in records:
            for observer in self._observers:
                try:
                    observer(record)
                except Exception as exc:
                    self.remove_observer(observer)
                    loggers.logerr(f"control observer {observer!r} raised {exc!r}; it was removed")
