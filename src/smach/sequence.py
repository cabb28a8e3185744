"""``Sequence``: a StateMachine whose states are chained by one connector outcome."""

from __future__ import annotations

from collections.abc import Iterable

from smach.exceptions import InvalidStateError
from smach.state import State
from smach.state_machine import StateMachine

__all__ = ["Sequence"]


class Sequence(StateMachine):
    """States run in the order they were added; ``connector_outcome`` leads to the next.

    The last state's connector outcome falls through as the container outcome of the
    same name, so ``connector_outcome`` is normally also a container outcome.
    """

    def __init__(
        self,
        outcomes: Iterable[str],
        connector_outcome: str,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        if not isinstance(connector_outcome, str) or not connector_outcome:
            raise InvalidStateError(
                f"connector_outcome must be an outcome name, got {connector_outcome!r}"
            )
        super().__init__(outcomes, input_keys, output_keys)
        self._connector_outcome = connector_outcome

    def _connectors(self, label: str, state: State) -> list[str]:
        """Every state added leads to the next one on the connector outcome."""
        connector = self._connector_outcome
        if isinstance(state, State) and connector not in state.get_registered_outcomes():
            raise InvalidStateError(
                f"{self._path}/{label}: the sequence's connector outcome {connector!r} is not an "
                f"outcome of the state; its outcomes: {', '.join(state.get_registered_outcomes())}"
            )
        return [connector]
