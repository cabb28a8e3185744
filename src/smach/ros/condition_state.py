"""``ConditionState``: poll ``cond_cb(ud)`` until it is true, a number of times, or a timeout."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

import smach
from smach.ros.executor import seconds
from smach.ros.ros_state import RosState

__all__ = ["ConditionState"]


class ConditionState(RosState):
    """Outcomes ``true``, ``false``, ``preempted``.

    As in the ROS 2 original: ``poll_rate`` in Hz, at most ``max_checks`` calls of
    ``cond_cb`` (``-1``: until ``timeout``), ``timeout`` in seconds or a ``Duration``.
    A preempt interrupts the sleep between checks at once. An exception in
    ``cond_cb`` propagates (the container reports it as
    :class:`smach.InvalidUserCodeError`), as in the original.
    """

    def __init__(
        self,
        node: Any,
        cond_cb: Callable[..., Any],
        input_keys: Iterable[str] | None = None,
        poll_rate: float = 20.0,
        timeout: Any = None,
        max_checks: int = 1,
    ) -> None:
        super().__init__(node, outcomes=["true", "false", "preempted"], input_keys=input_keys)
        if not callable(cond_cb):
            raise smach.InvalidStateError("ConditionState: cond_cb must be callable")
        if poll_rate <= 0:
            raise smach.InvalidStateError(
                f"ConditionState: poll_rate must be > 0 Hz, got {poll_rate}"
            )
        self._adopt_interface(cond_cb, outcomes=False)
        self._cond_cb = cond_cb
        self._period = 1.0 / poll_rate
        self._timeout = seconds(timeout, "timeout")
        self._max_checks = max_checks

    def execute(self, ud: smach.UserData) -> str:
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        checks = 0
        while self._max_checks == -1 or checks < self._max_checks:
            if self.preempt_requested():
                return self._preempted()
            if deadline is not None and time.monotonic() >= deadline:
                break
            if self._cond_cb(ud):
                return "true"
            checks += 1
            if self._max_checks != -1 and checks >= self._max_checks:
                break
            pause = self._period
            if deadline is not None:
                pause = min(pause, max(0.0, deadline - time.monotonic()))
            if self.sleep(pause):
                return self._preempted()
        return "false"
