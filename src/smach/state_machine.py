"""``StateMachine``: run one child at a time, follow transitions on outcomes.

The transition function is "(current label, returned outcome) -> next label or
container outcome". Before a run the machine is compiled into a table of slots
(state, remapper, next-slot per outcome) so that each transition costs a few dict
lookups; construction calls mark the table dirty.

Preemption is lock-free on the hot path: the loop publishes the current slot before
reading the preempt flag, and ``request_preempt`` sets the flag before reading the
current slot, so at least one of them forwards the request to the running child.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from smach.container import Container, construction_method
from smach.events import Capture
from smach.exceptions import (
    InvalidStateError,
    InvalidTransitionError,
)
from smach.log import loggers
from smach.machine_runs import MachineRuns, Slot
from smach.runtime import Runtime
from smach.state import State
from smach.user_data import UserData
from smach.util import is_shutdown as _never
from smach.util import key_list, shutdown

__all__ = ["StateMachine"]

_monotonic = time.monotonic
_current_thread = threading.current_thread

# The text of a userdata's key list in the "starting" INFO line, by the keys: a
# program has few key sets, so formatting each once saves most of the line's cost
# when a logger is installed (bounded, in case keys are made up at run time).
_KEY_LISTS: dict[tuple[str, ...], str] = {}
_KEY_LISTS_MAX = 1024


class StateMachine(MachineRuns):
    """A container that runs its children one at a time, following transitions."""

    #: Whether a parent StateMachine runs this machine's runs in its own loop instead
    #: of calling ``execute`` (see ``run_children``): true unless the class replaces
    #: ``execute`` or ``run_children`` or wants its outcomes checked.
    _runs_inline = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._runs_inline = (
            cls.execute is Container.execute
            and cls.run_children is StateMachine.run_children
            and cls._outcome_checked
        )

    # Every target the table can return was checked to be an outcome of the machine.
    _outcome_checked = True

    def __init__(
        self,
        outcomes: Iterable[str],
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys)
        self._states: dict[str, State] = {}
        self._transitions: dict[str, dict[str, str | None]] = {}
        self._remappings: dict[str, dict[str, str]] = {}
        self._constants: dict[str, dict[str, Any]] = {}
        self._initial_state_label: str | None = None
        # The last added label, and the connector outcomes of its add_auto() that the
        # next add() links.
        self._last_added: tuple[str, list[str]] | None = None
        self._current_slot: Slot | None = None
        self._preempt_lock = threading.Lock()
        # The compiled slots by label, and the initial state's slot (set by compile_children).
        self._slots: tuple[dict[str, Slot], Slot] | None = None
        # The last run's final state and its outcome (terminal states, the log line).
        self._last_exit: tuple[str, str | None] = ("", None)

    # -- construction ------------------------------------------------------------------------
    @construction_method
    def add(
        self,
        label: str,
        state: State,
        transitions: Mapping[str, str | None] | None = None,
        remapping: Mapping[str, str] | None = None,
        constants: Mapping[str, Any] | None = None,
    ) -> State:
        """Add ``state`` under ``label``; the first added state is the initial state.

        ``transitions`` maps the state's outcomes to a state label, a container outcome,
        or ``None`` (fall through: the container returns the same outcome). Outcomes
        not listed fall through. ``remapping`` maps state key -> container key;
        ``constants`` are written into the container's userdata before every
        execution of this state. (In a :class:`~smach.sequence.Sequence`, the state
        also leads to the next one added on the sequence's connector outcome.)
        """
        connectors = self._connectors(label, state)
        return self._add(label, state, transitions, remapping, constants, connectors)

    def _connectors(self, label: str, state: State) -> Sequence[str]:
        """The outcomes of ``state`` that ``add`` links to the next state added (none)."""
        return ()

    @construction_method
    def add_auto(
        self,
        label: str,
        state: State,
        connector_outcomes: Iterable[str],
        transitions: Mapping[str, str | None] | None = None,
        remapping: Mapping[str, str] | None = None,
        constants: Mapping[str, Any] | None = None,
    ) -> State:
        """Add ``state``; its ``connector_outcomes`` lead to whatever is added next.

        Explicit transitions win over connectors.
        """
        connectors = key_list(connector_outcomes, "connector_outcomes")
        registered = state.get_registered_outcomes() if isinstance(state, State) else ()
        missing = [o for o in connectors if o not in registered]
        if missing:
            raise InvalidStateError(
                f"{self._path}/{label}: connector outcomes {missing} are not outcomes of the "
                f"state; its outcomes: {', '.join(registered) or 'none'}"
            )
        return self._add(label, state, transitions, remapping, constants, connectors)

    def _add(
        self,
        label: str,
        state: State,
        transitions: Mapping[str, str | None] | None,
        remapping: Mapping[str, str] | None,
        constants: Mapping[str, Any] | None,
        connectors: Sequence[str],
    ) -> State:
        if label in self._states:
            raise InvalidStateError(
                f"{self._path}: a state labelled {label!r} was already added; labels must be unique"
            )
        given = dict(transitions) if transitions else {}
        if given and isinstance(state, State):
            self.check_state_spec(label, state, given)
        self.adopt_child(label, state)
        table: dict[str, str | None] = dict.fromkeys(state._outcomes)
        table.update(given)
        if self._last_added is not None:
            previous, connected = self._last_added
            for outcome in connected:
                self._transitions[previous][outcome] = label
        self._states[label] = state
        self._transitions[label] = table
        self._remappings[label] = dict(remapping) if remapping else {}
        self._constants[label] = dict(constants) if constants else {}
        self._last_added = (
            label,
            [o for o in connectors if given.get(o) is None] if connectors else [],
        )
        if self._initial_state_label is None:
            self._initial_state_label = label
        self._invalidate()
        return state

    def check_state_spec(
        self, label: str, state: State, transitions: Mapping[str, str | None]
    ) -> None:
        """Every transition must be keyed on an outcome the state registered."""
        registered = state.get_registered_outcomes()
        unknown = [o for o in transitions if o not in registered]
        if unknown:
            raise InvalidTransitionError(
                f"{self._path}/{label}: transitions for {unknown}, which are not outcomes of "
                f"the state; its outcomes: {', '.join(registered) or 'none'}"
            )

    @construction_method
    def set_initial_state(
        self, initial_states: Sequence[str], userdata: UserData | None = None
    ) -> None:
        """Start the next run in ``initial_states[0]``, merging ``userdata`` in.

        The label is checked with the other consistency checks (``close()``,
        ``execute()``), not here: SMACH code may name the initial state before adding it.
        """
        labels = [initial_states] if isinstance(initial_states, str) else list(initial_states)
        if len(labels) != 1:
            raise InvalidStateError(
                f"{self._path}: a StateMachine has exactly one initial state, got {labels}"
            )
        self._initial_state_label = labels[0]
        self._invalidate()
        if userdata is not None:
            self._userdata.update(userdata)

    # -- validation ----------------------------------------------------------------------------
    def consistency_problems(self) -> list[str]:
        """Every reason this machine cannot run, one line each (empty if it can)."""
        problems: list[str] = []
        outcomes = self._outcomes
        if not self._states:
            problems.append(f"{self._path}: the state machine has no states")
            return problems
        if self._initial_state_label is None:
            problems.append(f"{self._path}: no initial state")
        elif self._initial_state_label not in self._states:
            problems.append(
                f"{self._path}: initial state {self._initial_state_label!r} (set_initial_state) "
                f"is not a child; add a state with that label or name one of: "
                f"{', '.join(self._states)}"
            )
        for label, table in self._transitions.items():
            registered = self._states[label].get_registered_outcomes()
            for outcome, target in table.items():
                where = f"{self._path}/{label}"
                if outcome not in registered:
                    problems.append(
                        f"{where}: transition on {outcome!r}, which is not an outcome of the state"
                    )
                elif target is None or target == "":
                    if outcome not in outcomes:
                        problems.append(
                            f"{where}: outcome {outcome!r} has no transition and is not an outcome "
                            f"of the container; map it to one of: "
                            f"{', '.join([*self._states, *outcomes])}"
                        )
                elif target not in self._states and target not in outcomes:
                    problems.append(
                        f"{where}: outcome {outcome!r} leads to unknown target {target!r}; "
                        f"add a state labelled {target!r} to {self._path}, add {target!r} to its "
                        f"outcomes, or change the transition to one of: states "
                        f"{list(self._states)} or container outcomes {list(outcomes)}"
                    )
        return problems

    def compile_children(self) -> None:
        slots = {
            label: Slot(
                label,
                state,
                self.child_remapper(label, state, self._remappings[label]),
                self._constants[label],
                f"{self._path}/{label}",
            )
            for label, state in self._states.items()
        }
        for label, slot in slots.items():
            for outcome, target in self._transitions[label].items():
                if target is None or target == "":
                    slot.next[outcome] = outcome
                elif target in slots:
                    slot.next[outcome] = slots[target]
                else:
                    slot.next[outcome] = target
        assert self._initial_state_label is not None  # (checked before compiling)
        self._slots = (slots, slots[self._initial_state_label])

    # -- execution -------------------------------------------------------------------------------
    def run_children(self) -> str | None:
        """The transition loop: run the current state, follow its outcome's transition.

        A step that somebody watches (listeners, runtime control, log lines) or that
        has a preempt request to pass on goes through :meth:`Container.step_child`;
        an unwatched one calls the child directly, which is all ``step_child`` would
        do for it.

        An unwatched child that is a plain StateMachine (``_runs_inline``) is not
        called: this loop takes its run over. :meth:`_enter_inline` does what
        ``Container.execute`` does before ``run_children()``, the loop goes on with
        the child's slots (its parent's loop variables kept on ``above``), and when
        the child ends, :meth:`_leave_inline` does what its ``run_children()`` and
        ``execute`` do at the end, and the parent's step goes on with the outcome.
        So a tree of nested machines runs in this one frame whatever its depth.
        (CPython 3.11 keeps frames in 16 KiB chunks and frees a chunk as soon as the
        frame at its base returns: a run two frames per level deep crossed a chunk
        boundary on every execution, an ``mmap``, a ``munmap`` and page faults each
        time, more of them where calls were made right at the boundary, depending on
        how deep the caller's stack was: see docs/performance.md.)
        """
        sm: MachineRuns = self
        slot: Slot = self._slots[1]  # type: ignore[index]  # (compiled before every run)
        label = ""
        # With capture listeners only, the state_exited + transition of a step are held
        # until the next state is entered (nothing else happens in between in this
        # thread) and the three go out in one call (see step_child's ``pending``).
        pending: tuple[Capture, ...] = ()
        bus = self._rt.bus
        # Whether INFO lines are wanted (decided once per top-level run).
        log = self._log_info
        # Log lines alone take a step through step_child only if this machine writes
        # a line when a state is entered (StateMachine writes none, as the original).
        log_steps = log and self._logs_entries
        watched: object = False
        # The machines above the one running (children run inline), innermost last; each
        # is in the step of its ``_current_slot``, the child running.
        above: list[MachineRuns] = []
        ascending = False  # (the machine running has ended, with ``result``)
        outcome: Any = None
        result: str | None = None
        if self._preempted_state is not None:
            self._preempted_state = None
        try:
            while True:
                if ascending:  # the machine running ended: its run ends, its parent goes on
                    held, pending = pending, ()  # (sent by the call that takes them)
                    if not above:
                        return sm._end_loop(slot, outcome, result, held, watched)
                    sm._leave_inline(slot, outcome, result, held, watched, above[-1])
                    sm = above.pop()
                    slot = sm._current_slot  # type: ignore[assignment]  # (its step: the child)
                    label = slot.label
                    log = sm._log_info
                    log_steps = log and sm._logs_entries
                    outcome = result
                    ascending = watched = False  # (a child is run inline only unwatched)
                # The default check never says yes; skip the call unless replaced.
                elif shutdown.check is not _never and shutdown.check():
                    result = None  # (the run stops before its next state)
                    ascending = True
                    continue
                else:
                    label = slot.label
                    sm._current_slot = slot  # publish before reading the flag (see module doc)
                    if slot.constants:
                        sm._userdata._data.update(slot.constants)
                    watched = bus.listeners or sm._local
                    if watched or log_steps or sm._preempt_requested:
                        held, pending = pending, ()  # (step_child sends them, even if it raises)
                        # Typed str: anything else fails the lookup below and is reported.
                        outcome = sm.step_child(
                            label, slot.state, slot.remapper, sm._thread, held, check=False,
                            report_exit=False,
                        )  # fmt: skip
                    elif slot.inline is not None:  # a plain StateMachine: run it here
                        child = slot.inline
                        held, pending = pending, ()  # (sent first by the call that takes them)
                        child._enter_inline(sm, label, slot.remapper, held)
                        above.append(sm)
                        sm, slot = child, child._slots[1]  # type: ignore[index]
                        log = child._log_info
                        log_steps = log and child._logs_entries
                        continue
                    else:
                        try:
                            outcome = slot.state.execute(slot.remapper)
                        except Exception as exc:
                            sm._raise_child_error(label, slot.state, exc)
                try:
                    target = slot.next[outcome]
                except (KeyError, TypeError):
                    sm._no_transition(slot, outcome)  # (returns on shutdown)
                    result = None
                    ascending = True
                    continue
                if target.__class__ is not Slot:  # a container outcome: this machine ends
                    result = target  # type: ignore[assignment]
                    ascending = True
                    continue
                if watched:
                    pending = sm._report_step(slot, outcome, target, sm._thread)
                elif log:  # (the line of _log_transition, without a call per transition)
                    loggers.loginfo(
                        f"State machine transitioning '{label}':'{outcome}'-->'{target.label}'"
                    )
                slot = target
        except BaseException as exc:
            self._unwind(exc, above, sm, pending)

    def _start_states(self) -> list[str]:
        # (Never None during a run: the consistency check saw to it.)
        return [self._initial_state_label]  # type: ignore[list-item]

    def _terminal_states(self) -> list[str]:
        return [self._last_exit[0]]

    def _attach(self, runtime: Runtime, path: str) -> None:
        super()._attach(runtime, path)
        for slot in self._slots[0].values() if self._slots else ():
            slot.path = f"{path}/{slot.label}"  # (slots hold the children's paths)

    # -- preemption ------------------------------------------------------------------------------
    def request_preempt(self) -> None:
        # Our own flag only: the running child is reached once, through
        # _preempt_current (Container.request_preempt would forward a second time).
        super(Container, self).request_preempt()
        slot = self._current_slot
        if slot is not None:
            self._preempt_current(slot.state)

    def _preempt_current(self, state: State) -> None:
        with self._preempt_lock:
            previous = self._preempted_state
            if previous is state:
                if not state._preempt_requested:
                    state.request_preempt()
                return
            if previous is not None:
                previous.recall_preempt()
            self._preempted_state = state
        state.request_preempt()

    def _forward_preempt(self, state: State) -> None:
        """Before running ``state`` with our flag set: let the request flow or stop it."""
        previous = self._preempted_state
        if previous is None or previous._preempt_requested:
            # Nobody has handled the request yet: it flows to the next state.
            self._preempt_current(state)
        else:
            # The last preempted state serviced it; it chose where to go from there.
            self._clear_preempt()
            self._preempted_state = None

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        for name in ("_preempt_lock", "_slots", "_current_slot", "_preempted_state"):
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        self._preempt_lock = threading.Lock()
        self._slots = None
        self._current_slot = None

    # -- introspection -----------------------------------------------------------------------------
    def get_children(self) -> dict[str, State]:
        return self._states

    def get_initial_states(self) -> list[str]:
        return [self._initial_state_label] if self._initial_state_label is not None else []

    def get_active_states(self) -> list[str]:
        slot = self._current_slot
        return [slot.label] if slot is not None else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        return [
            (outcome, label, target if target != "" else None)
            for label, table in self._transitions.items()
            for outcome, target in table.items()
        ]

    def _log_started(self) -> None:
        keys = tuple(self._userdata._data)
        shown = _KEY_LISTS.get(keys)
        if shown is None:  # (the list's text costs more than the rest of the line)
            shown = str([*keys])
            if len(_KEY_LISTS) < _KEY_LISTS_MAX:
                _KEY_LISTS[keys] = shown
        loggers.loginfo(
            f"State machine starting in initial state '{self._initial_state_label}' with "
            f"userdata: \n\t{shown}"
        )

    def _log_transition(self, source: str, outcome: str, target: str) -> None:
        loggers.loginfo(f"State machine transitioning '{source}':'{outcome}'-->'{target}'")

    def _log_terminated(self, outcome: str | None) -> None:
        label, last = self._last_exit
        loggers.loginfo(f"State machine terminating '{label}':'{last}':'{outcome}'")
