"""``RosState`` (a state bound to an rclpy node) and ``SmachNode`` (a self-spinning node)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import smach
from smach.ros._api import Node, SingleThreadedExecutor
from smach.ros.executor import SmachExecutor

__all__ = ["RosState", "SmachNode"]

#: How often waits re-check conditions that do not wake them (the ROS graph).
POLL_PERIOD = 0.05


class RosState(smach.State):
    """A :class:`smach.State` that talks to ROS through ``node``.

    ``node`` names things (namespace, remapping, ``~``) and logs; the ROS entities
    live on smach's helper node (see :mod:`smach.ros.executor`), so the state works
    whether or not, and however, ``node`` is spun.
    """

    def __init__(
        self,
        node: Any,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        io_keys: Iterable[str] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys, io_keys)
        if node is None or not hasattr(node, "resolve_topic_name"):
            raise smach.InvalidStateError(
                f"{type(self).__name__} needs an rclpy Node as its first argument, got {node!r}"
            )
        self._node = node
        # Set by every callback that concerns the waiting execute() and by preempts.
        self._wake = threading.Event()

    @property
    def node(self) -> Any:
        """The user's rclpy node this state was built with."""
        return self._node

    def _helper(self) -> SmachExecutor:
        return SmachExecutor.for_node(self._node)

    def request_preempt(self) -> None:
        """Ask the state to stop; returns at once (the state winds down in execute)."""
        super().request_preempt()
        self._wake.set()

    def _wait(self, timeout: float | None) -> None:
        """Sleep until woken (a callback or a preempt) or ``timeout`` seconds passed.

        The event is cleared after waking; callers re-check every condition after
        each call, so nothing set meanwhile is lost.
        """
        self._wake.wait(None if timeout is None else max(0.0, timeout))
        self._wake.clear()

    def _wait_until(self, ready: Callable[[], bool], timeout: float | None) -> str:
        """Poll ``ready()`` until true: returns ``'ready'``, ``'preempted'`` or ``'timeout'``."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if self.preempt_requested():
                return "preempted"
            if ready():
                return "ready"
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return "timeout"
            self._wait(POLL_PERIOD if left is None else min(POLL_PERIOD, left))

    #: What the state talks to (service, action, topic name), for error messages.
    _ros_name: str = ""

    def _callback(
        self,
        what: str,
        cb: Callable[..., Any] | None,
        args: Sequence[Any] | None,
        kwargs: Mapping[str, Any] | None,
    ) -> tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]] | None:
        """Check a user callback, adopt its declared interface, bind its extra arguments."""
        if cb is None:
            return None
        if not callable(cb):
            raise smach.InvalidStateError(
                f"{type(self).__name__} {self._ros_name!r}: {what} must be callable, got {cb!r}"
            )
        self._adopt_interface(cb)
        return cb, tuple(args or ()), dict(kwargs or {})

    def _preempted(self) -> str:
        self.service_preempt()
        return "preempted"

    def _fail(self, message: str) -> str:
        smach.logerr(f"{self.path or type(self).__name__}: {message}")
        return "aborted"


class SmachNode(Node):  # type: ignore[misc]
    """An rclpy node with its own single-threaded executor; ``start()`` spins it in a thread.

    Kept from the ROS 2 smach_ros for ported code. smach's own states do not need
    the node to be spun (see :mod:`smach.ros.executor`); your subscriptions, timers
    and services on it do.
    """

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._smach_executor: Any = SingleThreadedExecutor(context=self.context)
        self._smach_executor.add_node(self)
        self._smach_thread: threading.Thread | None = None
        self._smach_running = False

    def start(self) -> None:
        """Spin this node in a daemon thread until :meth:`stop` or shutdown."""
        if self._smach_thread is not None:
            return
        self._smach_running = True
        self._smach_thread = threading.Thread(
            target=self._smach_spin, name=f"spin-{self.get_name()}", daemon=True
        )
        self._smach_thread.start()

    def _smach_spin(self) -> None:
        while self._smach_running and self.context.ok():
            try:
                self._smach_executor.spin_once(timeout_sec=0.1)
            except Exception:
                if self.context.ok() and self._smach_running:
                    raise
                break

    def stop(self) -> None:
        self._smach_running = False
        self.join()

    def join(self, timeout: float | None = None) -> None:
        if self._smach_thread is not None:
            self._smach_thread.join(timeout)
