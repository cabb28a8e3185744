"""How a StateMachine's run ends, and how a parent machine's loop runs a child machine.

:class:`Slot` is a compiled child of a StateMachine (what one step of its loop needs).
:class:`MachineRuns` is the part of :class:`~smach.state_machine.StateMachine` that
ends a run of its loop (the last state's exit, the held captures) and that lets a
parent's loop take a child machine's run over: ``StateMachine.run_children`` runs an
unwatched child that is a plain StateMachine in its own loop, not by a call, so a
tree of nested machines runs in one Python frame whatever its depth. The methods here
do, for such a child, what ``Container.execute`` and the child's own
``run_children`` would have done around its loop, in the same order, and what their
frames would have done with an error (the error event, the running flag, the
parent's wrapping of a child's error).

Why not a call: CPython 3.11 keeps frames in 16 KiB chunks and frees a chunk as soon
as the frame at its base returns. A run two frames per level deep crossed a chunk
boundary on every execution (an ``mmap``, a ``munmap`` and page faults each time), and
more often where calls were made right at the boundary; how often depended on how
deep the caller's stack happened to be, so the same nested machine ran at different
speeds in different processes (docs/performance.md, "Nested machines").
"""

from __future__ import annotations

import threading
import time
from typing import Any, ClassVar, NoReturn

from smach.container import Container
from smach.events import Capture, StateExited, Transition
from smach.exceptions import InvalidOutcomeError, InvalidStateError, InvalidUserCodeError
from smach.state import State
from smach.user_data import Remapper, UserData
from smach.util import shutdown

__all__ = ["MachineRuns", "Slot"]

_monotonic = time.monotonic
_current_thread = threading.current_thread


class Slot:
    """A compiled child: everything one step of the loop needs."""

    __slots__ = ("constants", "inline", "label", "next", "path", "remapper", "state")

    def __init__(
        self, label: str, state: State, remapper: Remapper, constants: dict[str, Any], path: str
    ) -> None:
        self.label = label
        self.state = state
        self.remapper = remapper
        self.constants = constants or None  # None: nothing to write (one test per step)
        self.path = path  # the child's path in events (slots are recompiled on adoption)
        self.next: dict[str, Slot | str] = {}
        # The child itself when the parent's loop takes its runs over (a plain
        # StateMachine: see StateMachine.run_children), else None.
        self.inline: MachineRuns | None = (
            state if isinstance(state, MachineRuns) and state._runs_inline else None
        )


class MachineRuns(Container):
    """Ending a StateMachine's loop, and running a child machine inline (mixed into
    ``StateMachine``)."""

    #: Whether a parent StateMachine runs this machine's runs in its own loop instead
    #: of calling ``execute`` (set per class by StateMachine).
    _runs_inline: ClassVar[bool] = False
    # The state last asked to preempt; set on the instance only by a preemption (an
    # instance keeps at most 29 attributes: see Container, ``_start_cbs``).
    _preempted_state: State | None = None
    _current_slot: Slot | None
    _last_exit: tuple[str, str | None]
    _slots: tuple[dict[str, Slot], Slot] | None

    def _end_loop(
        self,
        slot: Slot,
        outcome: str,
        result: str | None,
        pending: tuple[Capture, ...],
        watched: object,
    ) -> str | None:
        """The end of this machine's loop: its last state ``slot`` returned ``outcome``
        and the run ends with ``result`` (``None``: smach is shutting down). Reports the
        last exit (when ``result`` is a container outcome), sends ``pending``."""
        try:
            if result is not None:
                if pending or watched or self._preempt_requested:
                    pending = self._end_run(slot, outcome, self._thread, pending)
                else:  # (what _end_run comes to when nobody watches and nothing is pending)
                    self._last_exit = (slot.label, outcome)
        finally:
            if pending:
                self._release(pending)
            self._current_slot = None
        return result

    def _enter_inline(
        self, parent: MachineRuns, label: str, parent_ud: UserData, pending: tuple[Capture, ...]
    ) -> None:
        """``parent``'s loop takes this machine's run over (child ``label``, given
        ``parent_ud``): what ``Container.execute`` does up to ``run_children()``, and the
        start of that. ``parent``'s held captures (``pending``) are sent first. An error
        is raised as ``parent``'s step of a called child would."""
        if pending:
            parent._release(pending)
        try:
            if self._stale:
                self._prepare()
            if self._running:
                raise InvalidStateError(f"{self._path} is already running (in another thread?)")
        except Exception as exc:
            parent._raise_child_error(label, self, exc)
        self._running = True
        try:
            if self._copies_in:
                self._copy_input_keys(parent_ud)
            self._log_info = self._rt.log_info
            if self._log_info or self._local or self._rt.bus.listeners:
                self._announce_start()
            else:  # (nothing to announce: no call, once per level of a deep tree)
                self._thread = None
            if self._preempted_state is not None:
                self._preempted_state = None
        except BaseException as exc:
            self._fail_inline(exc, parent, label)
            raise

    def _leave_inline(
        self,
        slot: Slot,
        outcome: str,
        result: str | None,
        pending: tuple[Capture, ...],
        watched: object,
        parent: MachineRuns,
    ) -> None:
        """This machine's run, taken over by ``parent``'s loop, ended with ``result``:
        what its ``run_children()`` does then (:meth:`_end_loop`, written out here: one
        call less per level) and the end of ``Container.execute``. An error goes to
        the parent's loop, whose ``_unwind`` finishes this run if ``_running`` says it
        has not been finished."""
        try:
            if result is not None:
                if pending or watched or self._preempt_requested:
                    pending = self._end_run(slot, outcome, self._thread, pending)
                else:
                    self._last_exit = (slot.label, outcome)
        finally:
            if pending:
                self._release(pending)
            self._current_slot = None
        if result is not None:
            if self._rt.bus.listeners or self._local:
                self._emit_terminated(self._terminal_states(), result, self._thread)
            elif self._log_info:
                self._log_terminated(result)
            if self._copies_out:  # (the parent is in its step of this run: the slot's view)
                self._copy_output_keys(parent._current_slot.remapper)  # type: ignore[union-attr]
        self._running = False
        if self._rt.preempt_seen:
            self._after_run()

    def _fail_inline(self, exc: BaseException, parent: MachineRuns, label: str) -> None:
        """``exc`` ends this machine's run taken over by ``parent``'s loop: the error
        event and the end of the run (``Container.execute``'s ``except`` and
        ``finally``), then, for an ``Exception``, ``parent``'s step raises it (or its
        wrapper) as for a called child. (A ``BaseException`` goes on as it is.)"""
        try:
            try:
                if isinstance(exc, Exception):
                    self._emit_error(exc)
            finally:
                self._running = False
                if self._rt.preempt_seen:
                    self._after_run()
        except BaseException as late:  # (raised while ending the run: it goes on instead)
            exc = late
        if isinstance(exc, Exception):
            parent._raise_child_error(label, self, exc)

    def _unwind(
        self,
        exc: BaseException,
        above: list[MachineRuns],
        sm: MachineRuns,
        pending: tuple[Capture, ...],
    ) -> NoReturn:
        """``exc`` left the loop while it ran ``sm`` (this machine, or one run inline
        below it, ``above`` holding the machines in between): do what the frames of
        the nested calls would have done, innermost first, and raise what this
        machine's loop raises. For each machine: the loop's ``finally`` (``pending``
        sent); below this one, the end of its run (:meth:`_fail_inline`) unless it
        was over (``_running`` cleared: the error came from its last step), and its
        parent's step raising what it raised."""
        while True:
            try:
                if pending:
                    sm._release(pending)
            finally:
                sm._current_slot = None
            if not above:
                raise exc  # (its cause as the frames would have set it)
            child, sm, pending = sm, above.pop(), ()
            label = sm._current_slot.label  # type: ignore[union-attr]  # (its step: the child)
            try:
                if child._running:
                    child._fail_inline(exc, sm, label)
                elif isinstance(exc, Exception):
                    sm._raise_child_error(label, child, exc)
            except BaseException as raised:  # (what the parent's step raises)
                exc = raised

    def _end_run(
        self, slot: Slot, outcome: str, thread: str | None, pending: tuple[Capture, ...]
    ) -> tuple[Capture, ...]:
        """The last state returned ``outcome``, a container outcome: report its exit,
        service our preempt request if it did. Returns ``()`` (``pending`` sent)."""
        if pending:  # (listeners came or went during the run)
            self._release(pending)
        label = slot.label
        if self._rt.bus.listeners or self._local:
            self._emit_exited(label, outcome, thread)
        self._last_exit = (label, outcome)
        if self._preempt_requested and not slot.state._preempt_requested:
            self.service_preempt()
        return ()

    def _no_transition(self, slot: Slot, outcome: object) -> None:
        """``outcome`` of ``slot`` has no transition: raise the error, unless smach is
        shutting down (the state returned None; the machine then returns None)."""
        if outcome is None and shutdown.check():
            return
        raise self._missing_transition(slot, outcome) from None

    def _report_step(
        self, slot: Slot, outcome: str, target: Slot, thread: str | None
    ) -> tuple[Capture, ...]:
        """Report the exit of ``slot`` and the transition to ``target``: returns them held
        (for the next ``state_entered``) when only capture listeners listen."""
        bus = self._rt.bus
        held: tuple[Capture, ...] = ()
        if bus.event_listeners or self._local:
            self._emit_step(slot, outcome, target, thread)
        elif bus.sinks:
            t = _monotonic()
            label = slot.label
            if thread is None:  # (a listener came during a run that started unwatched)
                thread = _current_thread().name
            held = (
                (StateExited, slot.path, t, thread, label, outcome),
                (Transition, self._path, t, thread, label, outcome, target.label),
            )
        if self._log_info:
            self._log_transition(slot.label, outcome, target.label)
        return held

    def _emit_step(self, slot: Slot, outcome: str, target: Slot, thread: str | None) -> None:
        """``state_exited`` of ``slot`` then the ``transition`` to ``target`` (one time)."""
        t = _monotonic()
        if thread is None:
            thread = _current_thread().name
        label = slot.label
        path = self._path
        bus = self._rt.bus
        if bus.batch_sinks:
            pair = (
                (StateExited, slot.path, t, thread, label, outcome),
                (Transition, path, t, thread, label, outcome, target.label),
            )
            for sink in bus.batch_sinks:
                try:
                    sink(pair)
                except Exception as exc:
                    bus.sink_failed(sink, exc)
        if bus.event_listeners or self._local:
            self._deliver(
                StateExited(path=slot.path, time=t, thread=thread, label=label, outcome=outcome)
            )
            # Callbacks read get_active_states(): show the new state.
            self._current_slot = target
            self._deliver(
                Transition(
                    path=path,
                    time=t,
                    thread=thread,
                    source=label,
                    outcome=outcome,
                    target=target.label,
                )
            )
        else:
            self._current_slot = target

    def _missing_transition(self, slot: Slot, outcome: object) -> InvalidUserCodeError:
        if outcome in slot.state.get_registered_outcomes():
            return InvalidOutcomeError(
                f"state {self._path}/{slot.label} returned {outcome!r}, which was registered "
                f"after the state was added and has no transition"
            )
        return self._bad_outcome(slot.label, slot.state, outcome)
