"""States: the units of behaviour.

A state declares its interface up front (outcomes, input keys, output keys) and
implements one hook, :meth:`State.execute`. Containers (which are states too) check
the returned outcome, guard the userdata, emit events and wrap exceptions.

Preemption is cooperative. :meth:`State.request_preempt` sets a flag that a running
state polls with :meth:`State.preempt_requested`, or waits on with
:attr:`State.preempt_event` / :meth:`State.sleep`, which return at once on a request.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from smach.events import EventBus, PreemptRequested, PreemptServiced, stamp
from smach.exceptions import InvalidStateError
from smach.runtime import Runtime
from smach.user_data import UserData
from smach.util import has_smach_interface, key_list

__all__ = ["CBState", "State"]


class State:
    """Base class of every state.

    Subclasses call ``super().__init__(outcomes=[...], input_keys=[...], ...)`` and
    implement ``execute(self, ud)`` returning one of the declared outcomes.
    """

    # Where the state sits in a tree (set when a container adopts it); class-level
    # defaults keep construction cheap for states that are never watched.
    _rt: Runtime = Runtime()
    _path: str = ""
    _parent: State | None = None
    # Made on first use (preempt_event, sleep): most states never wait on it, and an
    # instance keeps its attributes inline only up to 29 (see docs/performance.md).
    _preempt_event: threading.Event | None = None

    def __init__(
        self,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        io_keys: Iterable[str] | None = None,
    ) -> None:
        io = key_list(io_keys, "io_keys") if io_keys is not None else []
        self._outcomes: dict[str, None] = dict.fromkeys(key_list(outcomes, "outcomes"))
        self._input_keys: dict[str, None] = (
            dict.fromkeys(key_list(input_keys, "input_keys") + io) if input_keys or io else {}
        )
        self._output_keys: dict[str, None] = (
            dict.fromkeys(key_list(output_keys, "output_keys") + io) if output_keys or io else {}
        )
        self._preempt_requested = False

    def execute(self, ud: UserData) -> str | None:
        """Do the state's work and return one of its registered outcomes."""
        raise NotImplementedError(f"{type(self).__name__} must implement execute(self, ud)")

    # -- interface ---------------------------------------------------------------
    def register_outcomes(self, outcomes: Iterable[str]) -> None:
        for o in key_list(outcomes, "outcomes"):
            self._outcomes[o] = None
        self._interface_changed()

    def get_registered_outcomes(self) -> tuple[str, ...]:
        return tuple(self._outcomes)

    def register_input_keys(self, keys: Iterable[str]) -> None:
        for k in key_list(keys, "input_keys"):
            self._input_keys[k] = None
        self._interface_changed()

    def register_output_keys(self, keys: Iterable[str]) -> None:
        for k in key_list(keys, "output_keys"):
            self._output_keys[k] = None
        self._interface_changed()

    def register_io_keys(self, keys: Iterable[str]) -> None:
        items = key_list(keys, "io_keys")
        self.register_input_keys(items)
        self.register_output_keys(items)

    def get_registered_input_keys(self) -> tuple[str, ...]:
        return tuple(self._input_keys)

    def get_registered_output_keys(self) -> tuple[str, ...]:
        return tuple(self._output_keys)

    def _adopt_interface(self, cb: object, *, outcomes: bool = True) -> None:
        """Add the keys (and outcomes) a callback declared with :func:`smach.cb_interface`."""
        if has_smach_interface(cb):
            self.register_input_keys(cb.get_registered_input_keys())  # type: ignore[attr-defined]
            self.register_output_keys(cb.get_registered_output_keys())  # type: ignore[attr-defined]
            if outcomes:
                self.register_outcomes(cb.get_registered_outcomes())  # type: ignore[attr-defined]

    def _interface_changed(self) -> None:
        """Tell the parent (which caches remappers built from our keys) to rebuild."""
        if self._parent is not None:
            self._parent._interface_changed()

    # -- preemption ----------------------------------------------------------------
    def request_preempt(self) -> None:
        """Ask this state to stop as soon as it can (returns at once)."""
        self._preempt_requested = True
        event = self._preempt_event
        if event is not None:
            event.set()
        rt = self._rt
        rt.preempt_seen = True
        if rt.bus.listeners:
            t, thread = stamp()
            rt.bus.emit(PreemptRequested(path=self._path, time=t, thread=thread))
        control = rt.control
        if control is not None:
            control.wake()  # a state held by a pause starts when preempted

    def service_preempt(self) -> None:
        """Acknowledge a preempt request: "I stopped because of it"."""
        self._clear_preempt()
        bus = self._rt.bus
        if bus.listeners:
            t, thread = stamp()
            bus.emit(PreemptServiced(path=self._path, time=t, thread=thread))

    def recall_preempt(self) -> None:
        """Withdraw a preempt request (used by containers)."""
        self._clear_preempt()

    def preempt_requested(self) -> bool:
        """Whether a preempt request is pending."""
        return self._preempt_requested

    def _clear_preempt(self) -> None:
        self._preempt_requested = False
        event = self._preempt_event
        if event is not None and event.is_set():
            event.clear()

    def _reset_preempt_tree(self) -> None:
        """Clear pending requests in this state and, for containers, below it."""
        if self._preempt_requested:
            self._clear_preempt()

    @property
    def preempt_event(self) -> threading.Event:
        """A :class:`threading.Event` that is set while a preempt is requested."""
        event = self._preempt_event
        if event is None:
            event = threading.Event()
            self._preempt_event = event
            # A request that raced with the creation must still wake waiters.
            if self._preempt_requested:
                event.set()
        return event

    def sleep(self, seconds: float) -> bool:
        """Sleep up to ``seconds``; return True at once if a preempt is requested.

        Typical use: ``if self.sleep(0.5): self.service_preempt(); return 'preempted'``.
        """
        if self._preempt_requested:
            return True
        return self.preempt_event.wait(max(0.0, seconds))

    # -- copying -----------------------------------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        # Events and locks belong to a running process, not to a copy.
        state = dict(self.__dict__)
        state.pop("_preempt_event", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._preempt_event = None

    # -- tree membership ------------------------------------------------------------
    def _attach(self, runtime: Runtime, path: str) -> None:
        """Join a tree: this state's events go to ``runtime.bus`` under ``path``.

        Containers call it when they adopt a child (``Container.adopt_child``).
        """
        self._rt = runtime
        self._path = path

    def _detach(self) -> None:
        """Leave the tree (a container replaced this child): no parent, no listeners."""
        self._parent = None
        self._rt = State._rt
        self._path = ""

    @property
    def _bus(self) -> EventBus:
        """The event bus of the tree this state belongs to (``self._rt.bus``)."""
        return self._rt.bus

    @property
    def path(self) -> str:
        """The state's path in its tree, e.g. ``/ROOT/FETCH/PICK`` (empty if unattached)."""
        return self._path

    def __repr__(self) -> str:
        where = f" at {self._path}" if self._path else ""
        return f"<{type(self).__name__}{where} outcomes={list(self._outcomes)}>"


class CBState(State):
    """A state that calls ``cb(ud, *cb_args, **cb_kwargs)`` and returns its result.

    If ``cb`` was decorated with :func:`smach.cb_interface`, its declared outcomes and
    keys are added to the state's.
    """

    def __init__(
        self,
        cb: Callable[..., Any],
        cb_args: Sequence[Any] | None = None,
        cb_kwargs: Mapping[str, Any] | None = None,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        io_keys: Iterable[str] | None = None,
    ) -> None:
        if not callable(cb):
            raise InvalidStateError(f"CBState needs a callable, got {cb!r}")
        super().__init__(outcomes, input_keys, output_keys, io_keys)
        self._cb = cb
        self._cb_args = tuple(cb_args or ())
        self._cb_kwargs = dict(cb_kwargs or {})
        self._adopt_interface(cb)

    def execute(self, ud: UserData) -> str | None:
        return self._cb(ud, *self._cb_args, **self._cb_kwargs)  # type: ignore[no-any-return]
