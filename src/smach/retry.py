"""``Retry``: re-run one child while it returns a retryable outcome.

Robot programs wrap flaky actions (grasps, service calls) in a bounded retry with a
pause between attempts. The pause is preempt-aware.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from smach.container import construction_method
from smach.exceptions import InvalidStateError
from smach.state import State
from smach.util import key_list
from smach.wrapper import Wrapper

__all__ = ["Retry"]


class Retry(Wrapper):
    """Run the child up to ``attempts`` times while it returns one of ``retry_outcomes``.

    Between attempts it waits ``backoff * backoff_factor ** (attempt - 1)`` seconds
    (at most ``max_backoff``); a preempt request ends the wait at once and the
    container returns ``preempted``. After the last attempt the child's last outcome
    is returned. :attr:`attempts_used` tells how many attempts the last run made.
    """

    def __init__(
        self,
        attempts: int = 3,
        retry_outcomes: Iterable[str] = ("aborted",),
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        backoff: float = 0.0,
        backoff_factor: float = 2.0,
        max_backoff: float | None = None,
    ) -> None:
        if not isinstance(attempts, int) or attempts < 1:
            raise InvalidStateError(f"Retry attempts must be an integer >= 1, got {attempts!r}")
        if backoff < 0 or backoff_factor < 1:
            raise InvalidStateError(
                f"Retry needs backoff >= 0 and backoff_factor >= 1, got {backoff!r} and "
                f"{backoff_factor!r}"
            )
        super().__init__(outcomes, input_keys, output_keys)
        self.attempts = attempts
        self.retry_outcomes = tuple(key_list(retry_outcomes, "retry_outcomes"))
        self.backoff = backoff
        self.backoff_factor = backoff_factor
        self.max_backoff = max_backoff
        self.attempts_used = 0

    @construction_method
    def add(self, label: str, state: State, remapping: Mapping[str, str] | None = None) -> State:
        """Set the child to retry; its outcomes must include every retry outcome."""
        missing = [o for o in self.retry_outcomes if o not in state.get_registered_outcomes()]
        if missing:
            raise InvalidStateError(
                f"{self._path}/{label}: retry outcomes {missing} are not outcomes of the child "
                f"({', '.join(state.get_registered_outcomes())}); pass retry_outcomes=[...]"
            )
        return super().add(label, state, remapping)

    def consistency_problems(self) -> list[str]:
        problems = super().consistency_problems()
        if self._child is not None:
            registered = self._child.get_registered_outcomes()
            problems += [
                f"{self._path}: retry outcome {o!r} is not an outcome of {self._label!r}: "
                f"{', '.join(registered)}"
                for o in self.retry_outcomes
                if o not in registered
            ]
        return problems

    def run(self, child: State, label: str) -> str:
        outcome = ""
        for attempt in range(1, self.attempts + 1):
            self.attempts_used = attempt
            outcome = self.run_child()
            if outcome not in self.retry_outcomes or attempt == self.attempts:
                break
            if self._preempt_requested or self.sleep(self._delay(attempt)):
                if "preempted" in self._outcomes:
                    self.service_preempt()
                    outcome = "preempted"
                break
            if self.is_observed():
                self.report_transition(label, outcome, label)
        return outcome

    def _delay(self, attempt: int) -> float:
        delay = self.backoff * self.backoff_factor ** (attempt - 1)
        return min(delay, self.max_backoff) if self.max_backoff is not None else delay

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        edges = super().get_internal_edges()
        if self._label is not None:
            edges += [(o, self._label, self._label) for o in self.retry_outcomes]
        return edges
