"""``Timeout``: preempt a child that runs too long and return a declared outcome.

The deadline is served by the shared timer thread (:mod:`smach.timers`). Preemption
is cooperative: the child is asked to stop at the deadline and the container returns
``timeout_outcome`` once it has.
"""

from __future__ import annotations

from collections.abc import Iterable

from smach import timers
from smach.exceptions import InvalidStateError
from smach.state import State
from smach.wrapper import Wrapper

__all__ = ["Timeout"]


class Timeout(Wrapper):
    """Run the child; if it is still running after ``timeout`` seconds, preempt it.

    Returns the child's outcome if it finished in time, ``timeout_outcome`` otherwise.
    :attr:`timed_out` tells whether the last run hit the deadline.
    """

    def __init__(
        self,
        timeout: float,
        timeout_outcome: str = "timeout",
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        if not isinstance(timeout, int | float) or timeout <= 0:
            raise InvalidStateError(f"Timeout needs a timeout in seconds > 0, got {timeout!r}")
        self.extra_outcomes = ("preempted", timeout_outcome)
        super().__init__(outcomes, input_keys, output_keys)
        if outcomes is not None:
            self.register_outcomes([timeout_outcome])
        self.timeout = float(timeout)
        self.timeout_outcome = timeout_outcome
        self.timed_out = False

    def run(self, child: State, label: str) -> str:
        self.timed_out = False

        def expire() -> None:
            self.timed_out = True
            child.request_preempt()

        handle = timers.schedule(self.timeout, expire)
        try:
            outcome = self.run_child()
        finally:
            handle.cancel()
        if self.timed_out and not self._preempt_requested:
            # The request was ours, not the parent's: withdraw whatever is left of it.
            child.recall_preempt()
            return self.timeout_outcome
        return outcome
