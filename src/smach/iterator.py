"""``Iterator``: run one contained state once per item of an iterable.

Each item is written to the container's userdata under ``it_label`` before the
contained state runs; the contained state sees the userdata through a Remapper like
in every other container (declare ``it_label`` as an input key to read it).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from smach.container import Container, construction_method
from smach.exceptions import InvalidStateError, InvalidUserCodeError
from smach.log import loggers
from smach.state import State
from smach.user_data import Remapper, UserData
from smach.util import is_shutdown as _never
from smach.util import key_list, shutdown

__all__ = ["Iterator"]


class Iterator(Container):
    """Loop a contained state over items; stop on a break outcome or when exhausted."""

    def __init__(
        self,
        outcomes: Iterable[str],
        input_keys: Iterable[str],
        output_keys: Iterable[str],
        it: Iterable[Any] | Callable[[], Iterable[Any]] | None = None,
        it_label: str = "it_data",
        exhausted_outcome: str = "exhausted",
    ) -> None:
        names = key_list(outcomes, "outcomes")
        if exhausted_outcome not in names:
            names = [*names, exhausted_outcome]
        super().__init__(names, input_keys, output_keys)
        self._items: Iterable[Any] | Callable[[], Iterable[Any]] = it if it is not None else ()
        self._items_label = it_label
        self._exhausted_outcome = exhausted_outcome
        self._state_label: str | None = None
        self._state: State | None = None
        self._remapping: dict[str, str] = {}
        self._loop_outcomes: list[str] = []
        self._break_outcomes: list[str] = []
        self._final_outcome_map: dict[str, str] = {}
        # Compiled (see compile_children): the state's remapper, the loop and break outcomes. One
        # attribute: an instance keeps at most 29 (see Container, ``_start_cbs``).
        self._tables: tuple[Remapper, frozenset[str], frozenset[str]] | None = None
        self._index = 0

    # -- construction ----------------------------------------------------------------------------
    @construction_method
    def set_iteritems(
        self, it: Iterable[Any] | Callable[[], Iterable[Any]], it_label: str = "it_data"
    ) -> None:
        """Items to iterate: an iterable, or a callable returning one (called per run)."""
        self._items = it
        self._items_label = it_label

    @construction_method
    def set_contained_state(
        self,
        label: str,
        state: State,
        loop_outcomes: Iterable[str] | None = None,
        break_outcomes: Iterable[str] | None = None,
        final_outcome_map: Mapping[str, str] | None = None,
        remapping: Mapping[str, str] | None = None,
    ) -> State:
        """Set the one state run per item.

        Give ``loop_outcomes`` (every other outcome breaks) or ``break_outcomes``
        (every other outcome loops). ``final_outcome_map`` maps the outcome that ended
        the loop to a container outcome (unmapped outcomes pass through unchanged).
        """
        loops = key_list(loop_outcomes, "loop_outcomes")
        breaks = key_list(break_outcomes, "break_outcomes")
        if loops and breaks:
            raise InvalidStateError(
                f"{self._path}/{label}: give loop_outcomes or break_outcomes, not both"
            )
        self.adopt_child(label, state)
        registered = state.get_registered_outcomes()
        unknown = [o for o in [*loops, *breaks] if o not in registered]
        if unknown:
            raise InvalidStateError(
                f"{self._path}/{label}: loop/break outcomes {unknown} are not outcomes of the "
                f"state; its outcomes: {', '.join(registered)}"
            )
        if breaks:
            loops = [o for o in registered if o not in breaks]
        else:
            breaks = [o for o in registered if o not in loops]
        self._state_label = label
        self._state = state
        self._loop_outcomes = loops
        self._break_outcomes = breaks
        self._final_outcome_map = dict(final_outcome_map or {})
        self._remapping = dict(remapping or {})
        self._invalidate()
        return state

    def consistency_problems(self) -> list[str]:
        if self._state is None or self._state_label is None:
            return [f"{self._path}: the iterator has no contained state (set_contained_state)"]
        problems = []
        outcomes = [*self._break_outcomes, self._exhausted_outcome]
        for outcome in outcomes:
            mapped = self._final_outcome_map.get(outcome, outcome)
            if mapped not in self._outcomes:
                problems.append(
                    f"{self._path}/{self._state_label}: outcome {outcome!r} ends the loop as "
                    f"{mapped!r}, which is not an outcome of the iterator: "
                    f"{', '.join(self._outcomes)}; add it to final_outcome_map"
                )
        return problems

    def compile_children(self) -> None:
        state, label = self._state, self._state_label
        assert state is not None and label is not None
        self._tables = (
            self.child_remapper(label, state, self._remapping),
            frozenset(self._loop_outcomes),
            frozenset(self._break_outcomes),
        )

    # -- execution -------------------------------------------------------------------------------
    def run_children(self) -> str | None:
        """Run the contained state once per item; return the (mapped) final outcome."""
        state, label, tables = self._state, self._state_label, self._tables
        assert state is not None and label is not None and tables is not None
        remapper, loops, breaks = tables
        items = self._items() if callable(self._items) else self._items
        try:
            iterator = iter(items)
        except TypeError as exc:
            raise InvalidUserCodeError(
                f"{self._path}: the items to iterate are not iterable: {items!r}"
            ) from exc
        outcome: str | None = self._exhausted_outcome
        data = self._userdata._data
        it_label = self._items_label
        bus = self._rt.bus
        thread = self._thread
        log = self._log_info  # (decided once per top-level run)
        path = self._path
        outcomes = state._outcomes
        self._index = 0
        preempted = False
        while True:
            if shutdown.check is not _never and shutdown.check():
                return None
            try:
                item = next(iterator)
            except StopIteration:
                outcome = self._exhausted_outcome
                break
            except Exception as exc:
                raise InvalidUserCodeError(
                    f"{self._path}: the iterable raised {type(exc).__name__} while producing "
                    f"item {self._index}: {exc}"
                ) from exc
            data[it_label] = item
            if bus.listeners or self._local or self._preempt_requested:
                outcome = self.step_child(label, state, remapper, thread)
            else:  # nobody listens, no request to forward: _step inlined
                if log:
                    loggers.loginfo(f"Iterating item {self._index} of {path}")
                try:
                    outcome = state.execute(remapper)
                except Exception as exc:
                    self._raise_child_error(label, state, exc)
                if outcome not in outcomes:
                    raise self._bad_outcome(label, state, outcome)
            self._index += 1
            if self._preempt_requested and not state._preempt_requested:
                # The child serviced our request: stop here. (If it ignored the
                # request, it flows on to the next item, as between states.)
                self._clear_preempt()
                preempted = True
                break
            if outcome in breaks or (loops and outcome not in loops):
                break
            if bus.listeners or self._local:
                self.report_transition(label, outcome, label, thread)
        assert outcome is not None
        final = self._final_outcome_map.get(outcome, outcome)
        if preempted and final not in self._outcomes:
            # Stopped on a loop outcome: report the preemption if we can.
            final = "preempted" if "preempted" in self._outcomes else self._exhausted_outcome
        return final

    # -- introspection ---------------------------------------------------------------------------
    def get_children(self) -> dict[str, State]:
        if self._state is None or self._state_label is None:
            return {}
        return {self._state_label: self._state}

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: UserData | None = None
    ) -> None:
        unknown = [s for s in initial_states if s != self._state_label]
        if unknown:
            raise InvalidStateError(f"{self._path}: unknown children {unknown}")
        if userdata is not None:
            self._userdata.update(userdata)

    def get_initial_states(self) -> list[str]:
        return [self._state_label] if self._state_label is not None else []

    def get_active_states(self) -> list[str]:
        return [self._state_label] if self._running and self._state_label else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        label = self._state_label
        if label is None:
            return []
        edges: list[tuple[str, str, str | None]] = [(o, label, label) for o in self._loop_outcomes]
        edges += [(o, label, self._final_outcome_map.get(o, o)) for o in self._break_outcomes]
        return edges

    def _log_entered(self, label: str) -> None:
        loggers.loginfo(f"Iterating item {self._index} of {self._path}")

    def _log_transition(self, source: str, outcome: str, target: str) -> None:
        """No line per loop: the item's line says it (as in the original SMACH)."""
