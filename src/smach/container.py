"""The ``Container`` interface: a state that holds and runs other states.

Containers share five mechanisms, implemented here once:

* construction: ``with container:`` opens it on a per-thread construction stack so
  that class-level calls (``StateMachine.add(...)``) act on it; instance calls
  (``sm.add(...)``) act on that instance (the stack: :mod:`smach.construction`);
* the run protocol: :meth:`Container.execute` is the same for every container
  (compile once, refuse a second concurrent run, begin, started event, the
  container's own loop :meth:`Container.run_children`, terminated event, output
  keys, error event, after-run bookkeeping); a container type writes only
  ``run_children``, and runs each child through :meth:`Container.step_child`;
* scoping: each container owns a local :class:`UserData`; declared input keys are
  copied in from the parent at the start of a run, declared output keys copied out at
  the end; children see it through a :class:`Remapper`;
* events: every container reports to the event bus of its tree (held, with runtime
  control and the preempt and log switches, by the tree's
  :class:`~smach.runtime.Runtime`); the SMACH start,
  transition and termination callbacks are listeners of it; INFO log lines are
  written beside it (see :mod:`smach.container_events`);
* preemption: requests are forwarded to the running children; each top-level run
  ends with clean preempt flags in the whole tree.

A new container type subclasses :class:`Container`, adopts its children with
:meth:`Container.adopt_child` (:meth:`Container.replace_child` to swap one), gives
each the view :meth:`Container.child_remapper` builds, implements ``run_children``
(and, if it precomputes per-child tables, ``compile_children``) and the introspection methods
(``get_children``, ``get_initial_states``, ``get_active_states``,
``get_internal_edges``, ``set_initial_state``, ``consistency_problems``); see
docs/containers.md.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any, ClassVar, NoReturn, TypeVar

from smach.construction import _construction, _label_problem, construction_method
from smach.container_checks import ContainerChecks
from smach.container_events import ContainerEvents
from smach.container_scope import ContainerScope, CopyPlan
from smach.events import Capture
from smach.exceptions import (
    InvalidConstructionError,
    InvalidOutcomeError,
    InvalidStateError,
    InvalidUserCodeError,
    NoContainerOpenError,
    SmachError,
)
from smach.log import info_enabled
from smach.runtime import Runtime
from smach.state import State
from smach.user_data import Remapper, UserData, make_remapper

__all__ = ["Container", "construction_method"]

C = TypeVar("C", bound="Container")


class Container(ContainerEvents, ContainerChecks, ContainerScope, State):
    """Base class of every container (a state made of states)."""

    #: True where ``run_children`` can only return a declared outcome (checked before the run),
    #: so the protocol need not check it again.
    _outcome_checked: ClassVar[bool] = False

    def __init__(
        self,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys)
        self._userdata = UserData()
        self._rt = Runtime()
        self._path = "/ROOT"
        self._parent = None  # (on the instance: run loops read it on every level)
        # The views child_remapper() built since the last compile: retargeted when
        # this container joins another tree.
        self._views: list[Remapper] = []
        # (The SMACH callbacks: class-level empty tuples until one is registered.)
        self._local = ()
        self._log_info = False
        self._running = False
        # The name of the thread running this container, read once per run when
        # somebody listens (every event of the run's own loop comes from it).
        self._thread: str | None = None
        # Compiled state (see _prepare): run tables up to date; this container alone
        # checked since its last change; it and everything below checked.
        self._stale = True
        self._consistent = False
        self._subtree_ok = False
        # (True until _prepare knows better; then how to copy: see _copy_input_keys)
        self._copies_in: bool | CopyPlan = True
        self._copies_out: bool | CopyPlan = True

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
        """Drop whatever was compiled from the children and the userdata.

        Called when a child is added, the userdata object is replaced and when this
        container's or a child's interface changes; the next run (or ``close()``)
        checks and compiles again. The containers above lose their "subtree checked"
        mark, not their tables (they hold this container, not its insides).
        """
        self._stale = True
        self._consistent = False
        node: State | None = self
        while isinstance(node, Container) and node._subtree_ok:
            node._subtree_ok = False
            node = node._parent

    def _interface_changed(self) -> None:
        self._invalidate()
        super()._interface_changed()

    def child_remapper(
        self, label: str, state: State, remapping: Mapping[str, str] | None = None
    ) -> Remapper:
        """The view of this container's userdata that the child ``label`` gets as ``ud``.

        It enforces the child's declared keys, translates them through ``remapping``
        (child key -> container key) and reports writes to the tree's listeners.
        Build it in :meth:`compile_children` and reuse it for every run: it follows
        this container into whatever tree adopts it.
        """
        view = make_remapper(
            self._userdata,
            state.get_registered_input_keys(),
            state.get_registered_output_keys(),
            remapping,
            path=self._path,
            bus=self._rt.bus,
            writer=label,
        )
        self._views.append(view)
        if isinstance(state, ContainerScope):  # a container copies its keys through it
            state._plan_copies(view)
        return view

    _remapper = child_remapper  # (the name before the extension API was public)

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
        self._consistent = True
        # Compile now, so that the first run does not; a problem further down is
        # reported by that run (as it would be without this step).
        with contextlib.suppress(SmachError):
            self._prepare()

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

    def adopt_child(self, label: str, state: State) -> None:
        """Make ``state`` this container's child ``label``: check the label, set the
        child's parent and attach it (and everything below it) to this tree, at
        ``<this path>/<label>``, with the tree's listeners and runtime control.

        Store the child in the container's own tables as well (``get_children``).
        """
        problem = _label_problem(label)
        if problem:
            raise InvalidStateError(f"{self._path}: {problem}")
        if not isinstance(state, State):
            raise InvalidStateError(
                f"{self._path}/{label}: expected a smach.State, got {type(state).__name__}"
            )
        state._parent = self
        state._attach(self._rt, f"{self._path}/{label}")
        self._invalidate()  # (compiled again before the next run)

    _adopt_child = adopt_child  # (the name before the extension API was public)

    def replace_child(self, label: str, state: State, old: State | None = None) -> None:
        """Put ``state`` in the place of ``old`` (or of nothing) as the child ``label``.

        ``old`` leaves the tree (no parent, a runtime context of its own) and ``state``
        is adopted; what was compiled from the children is rebuilt before the next run.
        Also while this container runs: a container that builds its child per run (a
        plan) swaps it in with this. Store ``state`` in the container's own tables too.
        """
        if old is not None and old is not state:
            old._detach()
        self.adopt_child(label, state)

    def _attach(self, runtime: Runtime, path: str) -> None:
        old = self._rt
        if old is not runtime:
            old.merge_into(runtime)
        self._rt = runtime
        self._path = path
        bus = runtime.bus
        for view in self._views:
            view._retarget(path, bus)
        for label, child in self.get_children().items():
            child._attach(runtime, f"{path}/{label}")

    def _detach(self) -> None:
        self._parent = None
        own = Runtime()
        self._rt = own  # (so that nothing of the tree left is merged into it)
        self._attach(own, "/ROOT")

    def set_root_path(self, path: str) -> None:
        """Name this (top-level) container in event paths, e.g. ``/SM_ROOT``."""
        if not path.startswith("/") or (path.endswith("/") and path != "/"):
            raise InvalidStateError(
                f"a root path starts with '/' and has no trailing '/': {path!r}"
            )
        self._attach(self._rt, path.rstrip("/") or "")

    # -- the run protocol ---------------------------------------------------------------
    def execute(self, parent_ud: UserData | None = None) -> str | None:
        """Run the container; return its outcome (``None`` if smach is shutting down).

        The run protocol, the same for every container:

        1. compile, if anything changed since the last run (``_prepare``: the tree is
           checked once, the run tables are built);
        2. refuse a second run while one is going on;
        3. copy input keys in, decide who listens this run (``_begin``);
        4. ``container_started`` (``_announce_start``); then the container's own loop, ``run_children()``;
        5. the outcome checked against the declared ones; ``container_terminated``;
           output keys copied out (all skipped when ``run_children`` returned ``None``
           because ``smach.is_shutdown()`` became true);
        6. on an exception, an ``error`` event before it propagates;
        7. always: the running flag cleared, and preempt requests addressed to this
           run dropped (``_after_run``).
        """
        if self._stale:
            self._prepare()
        if self._running:
            raise InvalidStateError(f"{self._path} is already running (in another thread?)")
        self._running = True
        try:
            self._begin(parent_ud)
            self._announce_start()
            outcome = self.run_children()
            if outcome is None:
                return None
            if not self._outcome_checked and outcome not in self._outcomes:
                raise InvalidOutcomeError(
                    f"{self._path}: the {type(self).__name__} ended with {outcome!r}, which is "
                    f"not one of its outcomes: {', '.join(self._outcomes)}"
                )
            if self._rt.bus.listeners or self._local:
                self._emit_terminated(self._terminal_states(), outcome, self._thread)
            elif self._log_info:
                self._log_terminated(outcome)
            if parent_ud is not None and self._copies_out:
                self._copy_output_keys(parent_ud)
            return outcome
        except Exception as exc:
            self._emit_error(exc)
            raise
        finally:
            self._running = False
            if self._rt.preempt_seen:
                self._after_run()

    def run_children(self) -> str | None:
        """Hook: the container's own loop; return the container's outcome.

        Called by :meth:`execute` between the start and the end of the protocol, with
        the local userdata filled in and the compiled tables ready. Run each child
        with :meth:`step_child` (it forwards preemption, gives runtime control its
        say, emits the per-child events and log lines, wraps child errors and checks
        the outcome); emit :meth:`report_transition` between children if the container
        has transitions. Return ``None`` only when ``smach.is_shutdown()`` stopped
        the run. (Subclasses written before this hook was public override ``_run``.)
        """
        return self._run()

    def _run(self) -> str | None:
        raise NotImplementedError(f"{type(self).__name__} must implement run_children(self)")

    def _start_states(self) -> list[str]:
        """The states a run starts in (the ``container_started`` event's)."""
        return self.get_initial_states()

    def _terminal_states(self) -> list[str]:
        """The states the last run ended in (the ``container_terminated`` event's)."""
        return self._start_states()

    def _prepare(self) -> None:
        """Before a run (or at ``close()``): check the tree once, build the run tables."""
        if not self._subtree_ok:
            self._check_before_run()
        self._views.clear()
        self.compile_children()
        # Flags on the instance, so that a run does not touch the key dicts (a fresh
        # machine's first run pays a cache miss for every object it touches).
        self._copies_in = bool(self._input_keys)
        self._copies_out = bool(self._output_keys)
        self._stale = False

    def compile_children(self) -> None:
        """Hook: build this container's run tables (the children's
        :meth:`child_remapper` views, transition tables).

        Called once after every change (adopting or replacing a child, a new
        interface or userdata: see :meth:`_invalidate`), when everything below is
        known to be consistent; the run loop then only looks things up.
        (Subclasses written before this hook was public override ``_compile``.)
        """
        self._compile()

    def _compile(self) -> None:
        """The hook's name before the extension API was public (nothing by default)."""

    def request_preempt(self) -> None:
        """Ask this container to stop: set its flag, then forward to the running children."""
        super().request_preempt()
        if self._running:
            children = self.get_children()
            for label in self.get_active_states():
                children[label].request_preempt()

    def is_running(self) -> bool:
        # (A container that writes its own execute() is running while it has active states.)
        return self._running or bool(self.get_active_states())

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        state.pop("_views", None)  # (views of the userdata are rebuilt, never copied)
        # Copy plans name the parent's view: a copy plans again on its first run.
        state["_copies_in"] = bool(state.get("_copies_in"))
        state["_copies_out"] = bool(state.get("_copies_out"))
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        self._views = []
        self._stale = True  # a copy's tables are rebuilt (subclasses drop them in copies)

    # -- running helpers (also for containers that write their own execute) ------------
    def _begin(self, parent_ud: UserData | None) -> None:
        """Start a run: copy input keys in, decide whether log lines are wanted (also for
        a container that writes its own ``execute``).

        Whether INFO lines are wanted is decided once per top-level run (it costs a
        logging lookup) and shared through the tree's runtime context (``Runtime``)
        with the containers below.
        """
        if parent_ud is not None and self._copies_in:
            self._copy_input_keys(parent_ud)
        rt = self._rt
        if self._parent is None:
            rt.log_info = info_enabled()
        self._log_info = rt.log_info

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
        rt = self._rt
        if rt.preempt_seen:
            for child in self.get_children().values():
                child._reset_preempt_tree()
            if self._parent is None:
                rt.preempt_seen = False
                self._clear_preempt()

    def step_child(
        self,
        label: str,
        state: State,
        ud: UserData,
        thread: str | None = None,
        pending: tuple[Capture, ...] = (),
        *,
        check: bool = True,
        report_exit: bool = True,
    ) -> str:
        """Run the child ``label`` once with ``ud`` (its :meth:`child_remapper` view);
        return its outcome. Every container runs its children through this.

        In order: a pending preempt request of this container is forwarded to the
        child (:meth:`_forward_preempt`); runtime control (``Runtime.control``) may
        hold the child before it starts; ``state_entered`` goes out (or the INFO
        line); the child runs, an exception is wrapped with the child's path
        (:meth:`_child_error`); runtime control may replace the outcome (a forced
        one); an undeclared outcome is refused (unless ``check`` is false: a caller
        that looks the outcome up in its own table checks there); ``state_exited``
        goes out (unless ``report_exit`` is false: a caller that reports the exit
        with what follows it, a transition, does so itself).

        ``thread``: the running thread's name, if the caller has it. ``pending``:
        captures of this container that precede the child's ``state_entered`` (a
        state machine's previous exit and transition), sent in one call with it
        when only capture listeners listen.
        """
        if self._preempt_requested:
            pending = self._release(pending)
            self._forward_preempt(state)
        control = self._rt.control
        path = state._path
        if control is not None:
            pending = self._release(pending)
            control.enter(self, path, state)  # holds the child while paused
        self._report_entered(label, path, thread, pending)
        try:
            outcome = state.execute(ud)
        except Exception as exc:
            if control is not None:
                control.leave(path, state, None)
            self._raise_child_error(label, state, exc)
        if control is not None:  # a forced outcome replaces the returned one
            outcome = control.leave(path, state, outcome)
        if check and outcome not in state._outcomes:
            raise self._bad_outcome(label, state, outcome)
        if report_exit:
            if self._rt.bus.listeners or self._local:
                self._emit_exited(label, outcome, thread)  # (and the log line, if wanted)
            elif self._log_info:
                self._log_exited(label, outcome)
        return outcome  # type: ignore[return-value]  # (checked above, or by the caller)

    _step = step_child  # (the name before the extension API was public)

    def _forward_preempt(self, state: State) -> None:
        """Pass this container's pending preempt request on to ``state``, about to start."""
        state.request_preempt()

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

    def _raise_child_error(self, label: str, state: State, exc: Exception) -> NoReturn:
        """Raise what a step of the child ``label`` raises for ``exc`` (in the ``except``
        clause that caught it): ``exc`` itself when it already says where it happened
        (with its own cause), else the :meth:`_child_error` wrapper, caused by ``exc``."""
        error = self._child_error(label, state, exc)
        if error is exc:
            raise exc
        raise error from exc

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
