"""``Concurrence``: run every child at once and combine their outcomes.

Children run on a reusable thread pool; the calling thread runs children too
(whatever no pool thread has picked up yet), so a Concurrence of quick children
costs little more than running them in a row. The container's outcome is decided
by, in order of precedence, ``outcome_cb``, ``outcome_map`` and ``default_outcome``.
"""

from __future__ import annotations

import collections
import itertools
import threading
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from typing import Any, ClassVar

from smach import worker_pool
from smach.container import Container, construction_method
from smach.events import Event, StateEntered, StateExited
from smach.exceptions import InvalidStateError, InvalidUserCodeError
from smach.log import loggers
from smach.state import State
from smach.user_data import Remapper, UserData
from smach.util import key_list

__all__ = ["Concurrence"]

OutcomeMap = Mapping[str, Mapping[str, "str | Collection[str]"]]


class _Child:
    __slots__ = ("label", "outcomes", "remapper", "state")

    def __init__(self, label: str, state: State, remapper: Remapper) -> None:
        self.label = label
        self.state = state
        self.remapper = remapper
        self.outcomes = frozenset(state.get_registered_outcomes())


class _Run:
    """The bookkeeping of one execution."""

    __slots__ = (
        "done",
        "errors",
        "finished",
        "helper",
        "lock",
        "pending",
        "results",
        "size",
    )

    def __init__(self, children: list[_Child]) -> None:
        self.results: dict[str, str | None] = {c.label: None for c in children}
        self.pending = collections.deque(children)
        self.size = len(children)
        # next() on a count is atomic: the runner that draws ``size`` was the last.
        self.finished = itertools.count(1)
        self.lock = threading.Lock()
        # A latch: held until the last child finishes (cheaper than an Event).
        self.done = threading.Lock()
        self.done.acquire()
        self.errors: list[BaseException] = []
        # The pool task queued to run waiting children, if one is on its way.
        self.helper: Callable[[], None] | None = None


class Concurrence(Container):
    """A container whose children all run at the same time."""

    _transition_cb_events: ClassVar[tuple[type[Event], ...]] = (StateEntered, StateExited)
    # The outcome policy only chooses among declared outcomes (checked at construction).
    _outcome_checked = True
    # Whether a subclass overrides run_branch (set per class: one test per child).
    _branches_hooked: ClassVar[bool] = False

    def __init__(
        self,
        outcomes: Iterable[str],
        default_outcome: str | None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        outcome_map: OutcomeMap | None = None,
        outcome_cb: Callable[[dict[str, str | None]], str | None] | None = None,
        child_termination_cb: Callable[[dict[str, str | None]], bool | Sequence[str]] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys)
        names = list(self._outcomes)
        if not default_outcome and not outcome_map and not outcome_cb:
            raise InvalidStateError(
                "Concurrence needs an outcome policy: a default_outcome, an outcome_map or an "
                "outcome_cb"
            )
        if default_outcome is not None and (
            not isinstance(default_outcome, str) or default_outcome not in self._outcomes
        ):
            raise InvalidStateError(
                f"Concurrence default_outcome {default_outcome!r} is not one of its outcomes: "
                f"{', '.join(names)}"
            )
        normalised: dict[str, dict[str, frozenset[str]]] = {}
        for container_outcome, conditions in (outcome_map or {}).items():
            if container_outcome not in self._outcomes:
                raise InvalidStateError(
                    f"Concurrence outcome_map key {container_outcome!r} is not one of its "
                    f"outcomes: {', '.join(names)}"
                )
            normalised[container_outcome] = {
                label: frozenset(
                    [wanted] if isinstance(wanted, str) else key_list(wanted, "outcomes")
                )
                for label, wanted in conditions.items()
            }
        for name, cb in (
            ("outcome_cb", outcome_cb),
            ("child_termination_cb", child_termination_cb),
        ):
            if cb is not None and not callable(cb):
                raise InvalidStateError(f"Concurrence {name} must be callable, got {cb!r}")
        self._default_outcome = default_outcome
        self._outcome_map = normalised
        self._outcome_cb = outcome_cb
        self._child_termination_cb = child_termination_cb
        self._states: dict[str, State] = {}
        self._remappings: dict[str, dict[str, str]] = {}
        self._children: list[_Child] | None = None
        self._current_run: _Run | None = None
        self._child_outcomes: dict[str, str | None] = {}

    # -- construction -------------------------------------------------------------------------
    @construction_method
    def add(self, label: str, state: State, remapping: Mapping[str, str] | None = None) -> State:
        """Add a child; it starts together with the others on every execution."""
        if label in self._states:
            raise InvalidStateError(
                f"{self._path}: a child labelled {label!r} was already added; labels must be unique"
            )
        self.adopt_child(label, state)
        self._states[label] = state
        self._remappings[label] = dict(remapping or {})
        self._invalidate()
        return state

    def consistency_problems(self) -> list[str]:
        problems: list[str] = []
        if not self._states:
            problems.append(f"{self._path}: the concurrence has no children")
        for container_outcome, conditions in self._outcome_map.items():
            for label, wanted in conditions.items():
                if label not in self._states:
                    problems.append(
                        f"{self._path}: outcome_map[{container_outcome!r}] names unknown child "
                        f"{label!r}; children: {', '.join(self._states) or 'none'}"
                    )
                    continue
                registered = self._states[label].get_registered_outcomes()
                for outcome in sorted(wanted - set(registered)):
                    problems.append(
                        f"{self._path}: outcome_map[{container_outcome!r}] expects {outcome!r} "
                        f"from {label!r}, which is not one of its outcomes: {', '.join(registered)}"
                    )
        return problems

    def compile_children(self) -> None:
        self._children = [
            _Child(label, state, self.child_remapper(label, state, self._remappings[label]))
            for label, state in self._states.items()
        ]

    # -- execution ------------------------------------------------------------------------------
    def run_children(self) -> str | None:
        """Run all children at once; return the outcome chosen by the policy."""
        children = self._children
        assert children is not None
        run = _Run(children)
        self._child_outcomes = run.results
        self._current_run = run  # publish before reading the flag (see request_preempt)
        try:
            if self._preempt_requested:
                self._preempt_children(run, None)
            self._run_pending(run)
            run.done.acquire()
        finally:
            self._current_run = None
        if run.errors:
            raise run.errors[0]
        return self._decide(run, children)

    def _terminal_states(self) -> list[str]:
        return list(self._states)

    def _run_pending(self, run: _Run) -> None:
        """Run children nobody has started yet (the caller and pool threads do this).

        Before starting a child, a runner makes sure one pool task is on its way for
        the children still waiting. Quick children are thus all run by the caller with
        at most one hand-off, while each child that blocks lets exactly one more
        runner start, so every child still starts without waiting for the others.
        """
        pending = run.pending
        while True:
            try:
                child = pending.popleft()
            except IndexError:
                break
            if pending and run.helper is None:
                self._queue_helper(run)
            self._run_child(run, child)
        helper = run.helper
        if helper is not None and worker_pool.cancel(helper):
            with run.lock:
                if run.helper is helper:
                    run.helper = None

    def _queue_helper(self, run: _Run) -> None:
        with run.lock:
            if run.helper is not None:
                return

            def helper() -> None:
                with run.lock:
                    if run.helper is helper:
                        run.helper = None
                self._run_pending(run)

            run.helper = helper
        worker_pool.submit(helper)

    def run_branch(self, label: str, body: Callable[[], None]) -> None:
        """Hook: run one child's branch, ``body()``, in the thread that picked it up.

        Override it to wrap every branch (take a turn on a shared clock, hold a
        resource): call ``body()`` exactly once. The default just calls it.
        """
        body()

    def _run_child(self, run: _Run, child: _Child) -> None:
        if self._branches_hooked:
            self.run_branch(child.label, lambda: self._run_branch(run, child))
        else:
            self._run_branch(run, child)

    def _run_branch(self, run: _Run, child: _Child) -> None:
        label = child.label
        observed = self._rt.bus.listeners or self._local  # (log lines need no lock: see below)
        try:
            if observed or self._rt.control is not None:
                outcome = self.step_child(
                    label, child.state, child.remapper, check=False, report_exit=False
                )
            else:  # nobody listens, nothing controls: step_child would only do this
                try:
                    outcome = child.state.execute(child.remapper)  # type: ignore[assignment]
                except Exception as exc:
                    self._raise_child_error(label, child.state, exc)
        except Exception as error:
            self._child_failed(run, error)
            return
        if outcome not in child.outcomes:
            self._child_failed(run, self._bad_outcome(label, child.state, outcome))
            return
        if observed or self._child_termination_cb is not None:
            self._child_finished_watched(run, label, outcome, bool(observed))
        else:
            run.results[label] = outcome
            if self._log_info:
                self._log_exited(label, outcome)
        if next(run.finished) == run.size:
            run.done.release()

    def _forward_preempt(self, state: State) -> None:
        """Nothing: a Concurrence preempts its unfinished children itself."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._branches_hooked = cls.run_branch is not Concurrence.run_branch

    def _child_finished_watched(self, run: _Run, label: str, outcome: str, observed: bool) -> None:
        """Record an outcome, tell the listeners and ask child_termination_cb, in order."""
        with run.lock:
            run.results[label] = outcome
            try:
                if observed:
                    self._emit_exited(label, outcome)  # (and the log line, if wanted)
                elif self._log_info:
                    self._log_exited(label, outcome)
                to_preempt = self._termination_request(run)
            except Exception as exc:
                run.errors.append(exc)
                to_preempt = None
        if to_preempt != ():
            self._preempt_children(run, to_preempt)

    def _child_failed(self, run: _Run, error: BaseException) -> None:
        """A child raised or returned a bad outcome: stop the others, report at the end."""
        run.errors.append(error)
        self._preempt_children(run, None)
        if next(run.finished) == run.size:
            run.done.release()

    def _termination_request(self, run: _Run) -> Sequence[str] | None:
        """Ask child_termination_cb which children to stop: () none, None all, or labels."""
        cb = self._child_termination_cb
        if cb is None:
            return ()
        try:
            answer = cb(dict(run.results))
        except Exception as exc:
            raise InvalidUserCodeError(
                f"{self._path}: child_termination_cb raised {type(exc).__name__}: {exc}"
            ) from exc
        if not answer:
            return ()
        if answer is True:
            return None
        if isinstance(answer, str) or not isinstance(answer, Iterable):
            raise InvalidUserCodeError(
                f"{self._path}: child_termination_cb returned {answer!r}; expected True/False "
                f"or a list of child labels"
            )
        labels = list(answer)
        unknown = [lbl for lbl in labels if lbl not in run.results]
        if unknown:
            raise InvalidUserCodeError(
                f"{self._path}: child_termination_cb asked to stop unknown children {unknown}; "
                f"children: {', '.join(run.results)}"
            )
        return labels

    def _preempt_children(self, run: _Run, labels: Sequence[str] | None) -> None:
        """Preempt unfinished children (all of them, or those in ``labels``)."""
        for label, outcome in list(run.results.items()):
            if outcome is None and (labels is None or label in labels):
                self._states[label].request_preempt()

    def _decide(self, run: _Run, children: list[_Child]) -> str:
        results = run.results
        if self._preempt_requested:
            unserviced = [c for c in children if c.state._preempt_requested]
            for child in unserviced:
                child.state.recall_preempt()
                loggers.logwarn(f"{self._path}/{child.label} did not service a preempt request")
            if not unserviced:
                self.service_preempt()
                if "preempted" in self._outcomes:
                    return "preempted"
        if self._outcome_cb is not None:
            try:
                chosen = self._outcome_cb(dict(results))
            except Exception as exc:
                raise InvalidUserCodeError(
                    f"{self._path}: outcome_cb raised {type(exc).__name__}: {exc}"
                ) from exc
            if chosen:
                if not isinstance(chosen, str) or chosen not in self._outcomes:
                    raise InvalidUserCodeError(
                        f"{self._path}: outcome_cb returned {chosen!r}; outcomes of the "
                        f"concurrence: {', '.join(self._outcomes)}"
                    )
                return chosen
        best: str | None = None
        best_size = -1
        for container_outcome, conditions in self._outcome_map.items():
            if len(conditions) > best_size and all(
                results.get(label) in wanted for label, wanted in conditions.items()
            ):
                best, best_size = container_outcome, len(conditions)
        if best is not None:
            return best
        if self._default_outcome is None:
            raise InvalidUserCodeError(
                f"{self._path}: no outcome_map entry matched the children's outcomes {results} "
                f"and there is no default_outcome"
            )
        return self._default_outcome

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        state["_children"] = None
        state["_current_run"] = None
        return state

    # -- introspection ---------------------------------------------------------------------------
    def get_children(self) -> dict[str, State]:
        return self._states

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: UserData | None = None
    ) -> None:
        """All children always start; only ``userdata`` is merged in."""
        unknown = [s for s in initial_states if s not in self._states]
        if unknown:
            raise InvalidStateError(f"{self._path}: unknown children {unknown}")
        if userdata is not None:
            self._userdata.update(userdata)

    def get_initial_states(self) -> list[str]:
        return list(self._states)

    def get_active_states(self) -> list[str]:
        run = self._current_run
        if run is None:
            return []
        return [label for label, outcome in list(run.results.items()) if outcome is None]

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        return [
            (outcome, label, container_outcome)
            for container_outcome, conditions in self._outcome_map.items()
            for label, wanted in conditions.items()
            for outcome in sorted(wanted)
        ]

    def _log_started(self) -> None:
        loggers.loginfo(f"Concurrence starting with userdata: \n\t{list(self._userdata.keys())}")

    def _log_exited(self, label: str, outcome: str | None) -> None:
        loggers.loginfo(f"Concurrent state '{label}' returned outcome '{outcome}' on termination.")

    def _log_terminated(self, outcome: str | None) -> None:
        loggers.loginfo(f"Concurrent Outcomes: {dict(self._child_outcomes)}")
