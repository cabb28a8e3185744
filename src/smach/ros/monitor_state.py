"""``MonitorState``: watch a topic and decide on each message with ``cond_cb(ud, msg)``.

The subscription is created in the constructor and kept (as in the ROS 2 original);
messages that arrive while the state is not executing are ignored (the original
raised ``AttributeError`` on a message before the first execution). Messages are
queued by the executor thread and ``cond_cb`` runs in the thread executing the
state, so userdata is only touched there. ``cond_cb`` returning true counts a check
(``valid`` after ``max_checks`` of them; with ``max_checks=-1`` the state monitors
until ``cond_cb`` returns false); false, or an exception (a malformed message), gives
``invalid``. A preempt at any time gives ``preempted``: the wait is on one event
that both messages and preempts set, so no request can be lost (the original's
race, issue #67).
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any

import smach
from smach.ros.executor import seconds, subscription_events
from smach.ros.ros_state import RosState
from smach.ros.shared_node import node_optional

__all__ = ["MonitorState"]

#: Messages kept while cond_cb is busy; the oldest are dropped beyond this.
MESSAGE_QUEUE = 100


class MonitorState(RosState):
    """Outcomes ``valid``, ``invalid``, ``preempted``.

    ``timeout`` (seconds or ``Duration``, default none) is new: when it passes
    without a verdict the state returns ``valid`` if at least one check passed and
    ``max_checks`` is -1, else ``invalid``.
    """

    @node_optional
    def __init__(
        self,
        node: Any,
        topic: str,
        msg_type: Any,
        cond_cb: Callable[[smach.UserData, Any], Any],
        max_checks: int = -1,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        *,
        timeout: Any = None,
        qos: Any = 10,
    ) -> None:
        super().__init__(
            node,
            outcomes=["valid", "invalid", "preempted"],
            input_keys=input_keys,
            output_keys=output_keys,
        )
        if not callable(cond_cb):
            raise smach.InvalidStateError(f"MonitorState {topic!r}: cond_cb must be callable")
        self._cond_cb = cond_cb
        self._max_checks = max_checks
        self._timeout = seconds(timeout, "timeout")
        self._queue: collections.deque[Any] = collections.deque(maxlen=MESSAGE_QUEUE)
        self._listening = False
        self._lock = threading.Lock()
        helper = self._helper()
        self._resolved_name: str = node.resolve_topic_name(topic)
        self._helper_node: Any = helper.node
        self._subscription: Any = helper.node.create_subscription(
            msg_type,
            self._resolved_name,
            self._on_message,
            qos,
            callback_group=helper.callback_group,
            event_callbacks=subscription_events(self._resolved_name),
        )

    def _on_message(self, msg: Any) -> None:
        # Executor thread. Messages outside an execution are dropped.
        with self._lock:
            if not self._listening:
                return
            self._queue.append(msg)
        self._wake.set()

    def execute(self, ud: smach.UserData) -> str:
        with self._lock:
            self._queue.clear()
            self._listening = True
        try:
            return self._monitor(ud)
        finally:
            with self._lock:
                self._listening = False
                self._queue.clear()

    def _monitor(self, ud: smach.UserData) -> str:
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        checks = 0
        while True:
            if self.preempt_requested():
                return self._preempted()
            while True:
                with self._lock:
                    if not self._queue:
                        break
                    msg = self._queue.popleft()
                try:
                    ok = self._cond_cb(ud, msg)
                except Exception as exc:
                    smach.logerr(
                        f"{self.path or 'MonitorState'}: cond_cb raised {type(exc).__name__}: "
                        f"{exc} on a message from {self._resolved_name!r}"
                    )
                    return "invalid"
                if not ok:
                    return "invalid"
                checks += 1
                if 0 < self._max_checks <= checks:
                    return "valid"
                if self.preempt_requested():
                    return self._preempted()
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return "valid" if checks and self._max_checks == -1 else "invalid"
            self._wait(left)

    def destroy(self) -> None:
        """Release the subscription (the state cannot execute afterwards)."""
        self._helper_node.destroy_subscription(self._subscription)
