"""The ``Container`` interface: a state that holds and runs other states.

Containers share four mechanisms, implemented here once:

* construction: ``with container:`` opens it on a per-thread construction stack so
  that class-level calls (``StateMachine.add(...)``) act on it; instance calls
  (``sm.add(...)``) act on that instance;
* scoping: each container owns a local :class:`UserData`; declared input keys are
  copied in from the parent at the start of a run, declared output keys copied out at
  the end; children see it through a :class:`Remapper`;
* events: every container reports to the event bus of its tree; the SMACH start,
  transition and termination callbacks and the INFO log lines are listeners of it;
* preemption: requests are forwarded to the running children; each top-level run
  ends with clean preempt flags in the whole tree.

A new container type subclasses :class:`Container`, implements ``execute`` and the
introspection methods (``get_children``, ``get_initial_states``,
``get_active_states``, ``get_internal_edges``, ``set_initial_state``,
``check_consistency``) and uses the helpers below; see docs/containers.md.
"""

from __future__ import annotations

import contextlib
import functools
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any, ClassVar, Concatenate, Generic, ParamSpec, TypeVar

from smach.exceptions import (
    InvalidConstructionError,
    InvalidOutcomeError,
    InvalidStateError,
    InvalidTransitionError,
    InvalidUserCodeError,
    NoContainerOpenError,
    SmachError,
)
from smach.introspection.events import (
    ContainerStarted,
    ContainerTerminated,
    ErrorRaised,
    Event,
    EventBus,
    Listener,
    StateEntered,
    StateExited,
    Transition,
    stamp,
)
from smach.log import info_enabled
from smach.state import State
from smach.user_data import Remapper, UserData, make_remapper

__all__ = ["Container", "construction_method"]

_monotonic = time.monotonic
_current_thread = threading.current_thread

C = TypeVar("C", bound="Container")
P = ParamSpec("P")
R = TypeVar("R")


class _ConstructionStack(threading.local):
    def __init__(self) -> None:
        self.stack: list[Container] = []


_construction = _ConstructionStack()


class construction_method(Generic[C, P, R]):  # noqa: N801  (reads like a decorator)
    """A method that, called on the class, acts on the currently open container.

    ``StateMachine.add(...)`` inside ``with sm:`` adds to ``sm``; ``sm.add(...)`` adds
    to ``sm`` whether or not it is open.
    """

    def __init__(self, fn: Callable[Concatenate[C, P], R]) -> None:
        self._fn = fn
        functools.update_wrapper(self, fn)  # type: ignore[arg-type]

    def __get__(self, obj: C | None, objtype: type[C] | None = None) -> Callable[P, R]:
        fn = self._fn
        if obj is not None:
            return functools.partial(fn, obj)
        owner = objtype

        @functools.wraps(fn)
        def on_open_container(*args: P.args, **kwargs: P.kwargs) -> R:
            assert owner is not None
            return fn(owner._currently_opened_container(), *args, **kwargs)

        return on_open_container


def _label_problem(label: object) -> str | None:
    if not isinstance(label, str) or not label:
        return f"a state label must be a non-empty string, got {label!r}"
    if "/" in label:
        return f"state label {label!r} must not contain '/' (it separates path segments)"
    return None


class Container(State):
    """Base class of every container (a state made of states)."""

    #: Which of this container's own events trigger the SMACH transition callbacks.
    _transition_cb_events: ClassVar[tuple[type[Event], ...]] = (Transition,)

    def __init__(
        self,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys)
        self._userdata = UserData()
        self._bus = EventBus()
        self._path = "/ROOT"
        self._parent: Container | None = None
        self._start_cbs: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
        self._transition_cbs: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
        self._termination_cbs: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
        # Listeners of this container's own events only (callbacks, log lines).
        self._local: tuple[Listener, ...] = ()
        self._log_info = False

    # -- userdata --------------------------------------------------------------------
    @property
    def userdata(self) -> UserData:
        """The container's local userdata (its scope)."""
        return self._userdata

    @userdata.setter
    def userdata(self, value: UserData) -> None:
        if not isinstance(value, UserData):
            raise InvalidStateError(
                f"userdata must be a smach.UserData, got {type(value).__name__}"
            )
        self._userdata = value
        self._invalidate()

    def _invalidate(self) -> None:
        """Hook: drop whatever was compiled from the children and the userdata.

        Called when the userdata object is replaced and when this container's or a
        child's interface changes; the next run rebuilds it.
        """

    def _interface_changed(self) -> None:
        self._invalidate()
        super()._interface_changed()

    def _remapper(self, label: str, state: State, remapping: Mapping[str, str] | None) -> Remapper:
        return make_remapper(
            self._userdata,
            state.get_registered_input_keys(),
            state.get_registered_output_keys(),
            remapping,
            owner=self,
            writer=label,
        )

    def _copy_input_keys(self, parent_ud: UserData | None) -> None:
        if parent_ud is None:
            return
        local = self._userdata._data
        for key in self._input_keys:
            if key in parent_ud:
                local[key] = _raw_get(parent_ud, key)
            elif key not in local:
                sys.modules["smach"].logwarn(
                    f"{self._path}: input key {key!r} is not available in the parent userdata"
                )

    def _copy_output_keys(self, parent_ud: UserData | None) -> None:
        if parent_ud is None:
            return
        local = self._userdata._data
        for key in self._output_keys:
            if key in local:
                parent_ud[key] = local[key]

    # -- construction ------------------------------------------------------------------
    def open(self) -> None:
        """Make this the container that class-level construction calls act on."""
        _construction.stack.append(self)

    def close(self) -> None:
        """Stop construction and check the container; raises listing every problem."""
        stack = _construction.stack
        if not stack:
            raise InvalidStateError(f"close() of {self._path}: no container is open")
        if stack[-1] is not self:
            raise InvalidStateError(
                f"close() of {self._path}: the open container is {stack[-1]._path} "
                "(containers must be closed in the reverse order of opening)"
            )
        stack.pop()
        self.check_consistency()

    def __enter__(self: C) -> C:
        self.open()
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        if exc_type is None:
            self.close()
            return
        # Unwind the construction stack so a failed build leaves nothing open.
        stack = _construction.stack
        if self in stack:
            del stack[len(stack) - 1 - stack[::-1].index(self) :]

    @contextlib.contextmanager
    def opened(self: C, **kwargs: Any) -> Iterator[C]:
        """``with sm.opened(): ...`` (keyword arguments are accepted and ignored)."""
        del kwargs
        with self:
            yield self

    def is_opened(self) -> bool:
        stack = _construction.stack
        return bool(stack) and stack[-1] is self

    def assert_opened(self, msg: str = "") -> None:
        if not self.is_opened():
            raise InvalidConstructionError(msg or f"{self._path} is not open for construction")

    @staticmethod
    def _any_containers_opened() -> bool:
        return bool(_construction.stack)

    @classmethod
    def _currently_opened_container(cls: type[C]) -> C:
        stack = _construction.stack
        if not stack:
            raise NoContainerOpenError(
                f"{cls.__name__} construction call with no container open; "
                f"use 'with container:' or call the method on an instance"
            )
        top = stack[-1]
        if not isinstance(top, cls):
            raise InvalidStateError(
                f"{cls.__name__} construction call while a {type(top).__name__} "
                f"({top._path}) is open"
            )
        return top

    def _adopt_child(self, label: str, state: State) -> None:
        problem = _label_problem(label)
        if problem:
            raise InvalidStateError(f"{self._path}: {problem}")
        if not isinstance(state, State):
            raise InvalidStateError(
                f"{self._path}/{label}: expected a smach.State, got {type(state).__name__}"
            )
        state._parent = self
        state._adopt(self._bus, f"{self._path}/{label}")

    def _adopt(self, bus: EventBus, path: str) -> None:
        old = self._bus
        if old is not bus:
            for listener in old.listeners:
                bus.add(listener)
        self._bus = bus
        self._path = path
        for label, child in self.get_children().items():
            child._adopt(bus, f"{path}/{label}")

    def set_root_path(self, path: str) -> None:
        """Name this (top-level) container in event paths, e.g. ``/SM_ROOT``."""
        if not path.startswith("/") or (path.endswith("/") and path != "/"):
            raise InvalidStateError(
                f"a root path starts with '/' and has no trailing '/': {path!r}"
            )
        self._adopt(self._bus, path.rstrip("/") or "")

    # -- events and callbacks ------------------------------------------------------------
    def add_listener(self, listener: Listener) -> None:
        """Receive every event of the whole tree this container belongs to."""
        self._bus.add(listener)

    def remove_listener(self, listener: Listener) -> None:
        self._bus.remove(listener)

    def register_start_cb(self, start_cb: Callable[..., Any], cb_args: Sequence[Any] = ()) -> None:
        """``start_cb(userdata, initial_states, *cb_args)`` at the start of each run."""
        self._start_cbs.append((start_cb, tuple(cb_args)))
        self._refresh_local()

    def register_transition_cb(
        self, transition_cb: Callable[..., Any], cb_args: Sequence[Any] = ()
    ) -> None:
        """``transition_cb(userdata, active_states, *cb_args)`` after each transition."""
        self._transition_cbs.append((transition_cb, tuple(cb_args)))
        self._refresh_local()

    def register_termination_cb(
        self, termination_cb: Callable[..., Any], cb_args: Sequence[Any] = ()
    ) -> None:
        """``termination_cb(userdata, terminal_states, outcome, *cb_args)`` at the end."""
        self._termination_cbs.append((termination_cb, tuple(cb_args)))
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

    def _call_cbs(
        self,
        kind: str,
        cbs: list[tuple[Callable[..., Any], tuple[Any, ...]]],
        args: tuple[Any, ...],
    ) -> None:
        # Callbacks observe; a failing observer (say, an introspection publisher) must
        # not abort the robot's task. The error is logged with where it came from, and
        # the remaining callbacks still run.
        for cb, extra in cbs:
            try:
                cb(*args, *extra)
            except Exception as exc:
                sys.modules["smach"].logerr(
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

    def _refresh_local(self, log: bool | None = None) -> None:
        if log is None:
            log = self._log_info
        self._log_info = log
        local: list[Listener] = []
        if self._start_cbs or self._transition_cbs or self._termination_cbs:
            local.append(self._callbacks_listener)
        if log:
            local.append(self._log_event)
        self._local = tuple(local)

    def _log_event(self, event: Event) -> None:
        """Write the INFO line of one of this container's events (override per type)."""
        smach = sys.modules["smach"]
        if isinstance(event, ContainerStarted):
            smach.loginfo(
                f"{type(self).__name__} {self._path} starting in {list(event.initial_states)}"
            )
        elif isinstance(event, Transition):
            smach.loginfo(
                f"{type(self).__name__} {self._path} transitioning "
                f"'{event.source}':'{event.outcome}'-->'{event.target}'"
            )
        elif isinstance(event, ContainerTerminated):
            smach.loginfo(
                f"{type(self).__name__} {self._path} terminating "
                f"{list(event.terminal_states)} with outcome '{event.outcome}'"
            )

    def _observed(self) -> bool:
        """Whether anybody listens to this container's events right now."""
        return bool(self._bus.listeners or self._local)

    def _emit(self, event: Event) -> None:
        """Send one of this container's events to the tree's bus and to local listeners."""
        if self._bus.listeners:
            self._bus.emit(event)
        for listener in self._local:
            listener(event)

    def _deliver(self, event: Event) -> None:
        """Send an event the capture listeners already got to everybody else."""
        if self._bus.event_listeners:
            self._bus.deliver(event)
        for listener in self._local:
            listener(event)

    # Event builders, called only when _observed() is true. Capture listeners (journal,
    # viewer) get a tuple; an Event object is built only when somebody else listens.
    # ``thread`` may be passed by a caller that already knows it (a run's own thread).
    def _emit_started(self, initial_states: Sequence[str], thread: str | None = None) -> None:
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        states = tuple(initial_states)
        kind = type(self).__name__
        bus = self._bus
        if bus.sinks:
            capture = (ContainerStarted, self._path, t, thread, kind, states)
            for sink in bus.sinks:
                try:
                    sink(capture)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(
                ContainerStarted(
                    path=self._path,
                    time=t,
                    thread=thread,
                    container_type=kind,
                    initial_states=states,
                )
            )

    def _emit_entered(self, label: str, thread: str | None = None) -> None:
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        path = f"{self._path}/{label}"
        bus = self._bus
        if bus.sinks:
            capture = (StateEntered, path, t, thread, label)
            for sink in bus.sinks:
                try:
                    sink(capture)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(StateEntered(path=path, time=t, thread=thread, label=label))

    def _emit_exited(self, label: str, outcome: str | None, thread: str | None = None) -> None:
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        path = f"{self._path}/{label}"
        bus = self._bus
        if bus.sinks:
            capture = (StateExited, path, t, thread, label, outcome)
            for sink in bus.sinks:
                try:
                    sink(capture)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(
                StateExited(path=path, time=t, thread=thread, label=label, outcome=outcome)
            )

    def _emit_transition(
        self, source: str, outcome: str, target: str, thread: str | None = None
    ) -> None:
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        bus = self._bus
        if bus.sinks:
            capture = (Transition, self._path, t, thread, source, outcome, target)
            for sink in bus.sinks:
                try:
                    sink(capture)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(
                Transition(
                    path=self._path,
                    time=t,
                    thread=thread,
                    source=source,
                    outcome=outcome,
                    target=target,
                )
            )

    def _emit_terminated(
        self, terminal_states: Sequence[str], outcome: str | None, thread: str | None = None
    ) -> None:
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        states = tuple(terminal_states)
        bus = self._bus
        if bus.sinks:
            capture = (ContainerTerminated, self._path, t, thread, states, outcome)
            for sink in bus.sinks:
                try:
                    sink(capture)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(
                ContainerTerminated(
                    path=self._path,
                    time=t,
                    thread=thread,
                    terminal_states=states,
                    outcome=outcome,
                )
            )

    def _emit_error(self, exc: BaseException) -> None:
        if self._bus.listeners:
            t, thread = stamp()
            self._bus.emit(
                ErrorRaised(
                    path=self._path,
                    time=t,
                    thread=thread,
                    error_type=type(exc).__name__,
                    message=str(exc),
                )
            )

    # -- running helpers for container implementations ------------------------------------
    def _begin(self, parent_ud: UserData | None) -> None:
        """Start a run: copy input keys in, decide who listens this run.

        Whether INFO lines are wanted is decided once per top-level run (it costs a
        logging lookup) and shared through the bus with the containers below.
        """
        if parent_ud is not None and self._input_keys:
            self._copy_input_keys(parent_ud)
        bus = self._bus
        if self._parent is None:
            bus.log_info = info_enabled()
        if bus.log_info is not self._log_info:
            self._refresh_local(log=bus.log_info)

    def _end(self, parent_ud: UserData | None) -> None:
        """Finish a run normally: copy output keys out."""
        if parent_ud is not None and self._output_keys:
            self._copy_output_keys(parent_ud)

    def _after_run(self) -> None:
        """Always called when a run ends, normally or not.

        Preempt requests still pending below this container were addressed to an
        execution that is over: they are dropped so they cannot hit a later run of
        those states. The container's own flag is kept (it is how an unserviced
        request flows on to the parent's next state) unless this is the top level.
        """
        bus = self._bus
        if bus.preempt_seen:
            for child in self.get_children().values():
                child._reset_preempt_tree()
            if self._parent is None:
                bus.preempt_seen = False
                self._clear_preempt()

    def _child_error(self, label: str, state: State, exc: Exception) -> InvalidUserCodeError:
        """Wrap an exception raised by a child's execute(), naming the child's path.

        Errors that already name where they happened pass through unchanged: user-code
        errors, and smach's errors raised by a nested container.
        """
        if isinstance(exc, InvalidUserCodeError) or (
            isinstance(exc, SmachError) and isinstance(state, Container)
        ):
            return exc  # type: ignore[return-value]
        return InvalidUserCodeError(
            f"state {self._path}/{label} ({type(state).__name__}) raised "
            f"{type(exc).__name__}: {exc}"
        )

    def _bad_outcome(self, label: str, state: State, outcome: object) -> InvalidUserCodeError:
        declared = ", ".join(state.get_registered_outcomes()) or "none"
        return InvalidOutcomeError(
            f"state {self._path}/{label} ({type(state).__name__}) returned {outcome!r}; "
            f"declared outcomes: {declared}"
        )

    def _reset_preempt_tree(self) -> None:
        super()._reset_preempt_tree()
        for child in self.get_children().values():
            child._reset_preempt_tree()

    # -- the interface every container implements --------------------------------------------
    def __getitem__(self, label: str) -> State:
        children = self.get_children()
        if label not in children:
            raise KeyError(
                f"{self._path} has no child {label!r}; children: {', '.join(children) or 'none'}"
            )
        return children[label]

    def get_children(self) -> dict[str, State]:
        raise NotImplementedError

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: UserData | None = None
    ) -> None:
        raise NotImplementedError

    def get_initial_states(self) -> list[str]:
        raise NotImplementedError

    def get_active_states(self) -> list[str]:
        raise NotImplementedError

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        raise NotImplementedError

    def check_consistency(self) -> None:
        """Raise :class:`InvalidTransitionError` listing every problem of this container."""
        self._raise_problems(self.consistency_problems())

    def consistency_problems(self) -> list[str]:
        """Every reason this container (alone) cannot run, one line each."""
        raise NotImplementedError

    def _raise_problems(self, problems: list[str]) -> None:
        if problems:
            count = f"{len(problems)} problem{'s' if len(problems) > 1 else ''}"
            raise InvalidTransitionError(
                f"{_KIND_NAMES.get(type(self).__name__, type(self).__name__)} {self._path} is "
                f"inconsistent ({count}):\n  " + "\n  ".join(problems)
            )

    def subtree_problems(self) -> list[str]:
        """The consistency problems of this container and of every container below it."""
        problems: list[str] = []
        stack: list[State] = [self]
        while stack:
            node = stack.pop()
            if isinstance(node, Container):
                try:
                    problems.extend(node.consistency_problems())
                except NotImplementedError:
                    try:
                        node.check_consistency()
                    except SmachError as exc:
                        problems.append(f"{node._path}: {exc}")
                stack.extend(reversed(list(node.get_children().values())))
        return problems

    def _check_before_run(self) -> None:
        """Refuse to run if anything in the tree below is inconsistent (all problems at once)."""
        self._raise_problems(self.subtree_problems())

    def is_running(self) -> bool:
        return bool(self.get_active_states())


_KIND_NAMES = {
    "StateMachine": "state machine",
    "Concurrence": "concurrence",
    "Iterator": "iterator",
}


def _raw_get(ud: UserData, key: str) -> Any:
    """Read a key without the read-only wrapper (for copying between scopes)."""
    while isinstance(ud, Remapper):
        if key not in ud._in:
            ud._read(key)  # raises the undeclared-key error
        key = ud._remap.get(key, key)
        ud = ud._ud
    return ud._data[key]
