"""``ConditionState``: poll ``cond_cb(ud)`` until it is true, a number of times, or a timeout."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

import smach
from smach.ros.executor import seconds
from smach.ros.ros_state import RosState
from smach.ros.shared_node import node_optional

__all__ = ["ConditionState"]


class ConditionState(RosState):
    """Outcomes ``true``, ``false``, ``preempted``.

    Two signatures, as in the two originals:

    * ROS 2: ``ConditionState(node, cond_cb, input_keys, poll_rate=20.0, timeout, max_checks)``
      with ``poll_rate`` in Hz;
    * ROS 1: ``ConditionState(cond_cb, input_keys, poll_rate=0.05, timeout, max_checks)``
      (no node: the default node, see :mod:`smach.ros.shared_node`) with
      ``poll_rate`` the *period* between checks, in seconds, as ``rospy.sleep``
      took it.

    An rclpy ``Duration`` as ``poll_rate`` is a period in both forms. At most
    ``max_checks`` calls of ``cond_cb`` (``-1``: until ``timeout``; the ROS 1
    original made one more), ``timeout`` in seconds or a ``Duration``. A preempt
    interrupts the sleep between checks at once. An exception in ``cond_cb``
    propagates (the container reports it as :class:`smach.InvalidUserCodeError`).
    """

    @node_optional
    def __init__(
        self,
        node: Any,
        cond_cb: Callable[..., Any],
        input_keys: Iterable[str] | None = None,
        poll_rate: Any = None,
        timeout: Any = None,
        max_checks: int = 1,
    ) -> None:
        super().__init__(node, outcomes=["true", "false", "preempted"], input_keys=input_keys)
        if not callable(cond_cb):
            raise smach.InvalidStateError(
                f"ConditionState: cond_cb must be callable, got {cond_cb!r}"
            )
        self._adopt_interface(cond_cb, outcomes=False)
        self._cond_cb = cond_cb
        self._period = _period(poll_rate, ros1=getattr(self, "_default_node_used", False))
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


def _period(poll_rate: Any, *, ros1: bool) -> float:
    """Seconds between checks from either original's ``poll_rate``."""
    if poll_rate is None:
        return 0.05  # 20 Hz, the default of both originals
    if isinstance(getattr(poll_rate, "nanoseconds", None), int):
        period = seconds(poll_rate, "poll_rate")
        assert period is not None
    elif isinstance(poll_rate, int | float) and not isinstance(poll_rate, bool):
        if poll_rate <= 0:
            unit = "s (ROS 1 form: a period)" if ros1 else "Hz (ROS 2 form: a rate)"
            raise smach.InvalidStateError(
                f"ConditionState: poll_rate must be > 0 {unit}, got {poll_rate}"
            )
        period = float(poll_rate) if ros1 else 1.0 / poll_rate
    else:
        raise smach.InvalidStateError(
            f"ConditionState: poll_rate must be a number or an rclpy Duration, got {poll_rate!r}"
        )
    if period <= 0:
        raise smach.InvalidStateError(f"ConditionState: poll_rate period must be > 0, got {period}")
    return period
