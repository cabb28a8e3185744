"""``RosState`` (a state bound to an rclpy node) and ``SmachNode`` (a self-spinning node)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import smach
from smach.ros._api import InvalidHandle, Node, RCLError, SingleThreadedExecutor
from smach.ros.executor import SmachExecutor

__all__ = ["Liveness", "RosState", "SmachNode", "StateAbort"]

#: A user callback bound to its extra arguments (see ``RosState._callback``).
Bound = tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]]


class StateAbort(Exception):  # noqa: N818  (control flow inside execute)
    """Something the state needed failed: it returns ``aborted`` with this message."""


#: How often waits re-check conditions that do not wake them (the ROS graph).
POLL_PERIOD = 0.05


class Liveness:
    """Whether a peer (service or action server) is still in the ROS graph, checked
    every ``period`` seconds (None: never) from ``start``. Two failed checks in a row
    mean it is gone: a single miss can be a graph update in flight."""

    def __init__(self, ready: Callable[[], bool], period: float | None, start: float) -> None:
        self._ready = ready
        self._period = period
        self.next_check = None if period is None else start + period
        self._misses = 0

    def lost(self, now: float) -> bool:
        """Check if one is due at ``now``; True once the peer is gone."""
        if self.next_check is None or now < self.next_check:
            return False
        self.next_check = now + (self._period or POLL_PERIOD)
        self._misses = 0 if self._ready() else self._misses + 1
        return self._misses >= 2


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

    #: The user's own liveness check of the server (``peer_alive``; None: none).
    _peer_alive: Callable[[], bool] | None = None

    def _set_peer_alive(self, peer_alive: Callable[[], bool] | None) -> None:
        if peer_alive is not None and not callable(peer_alive):
            raise smach.InvalidStateError(
                f"{type(self).__name__} {self._ros_name!r}: peer_alive must be callable, "
                f"got {peer_alive!r}"
            )
        self._peer_alive = peer_alive

    def _liveness(self, ready: Callable[[], bool], period: float | None, start: float) -> Liveness:
        """The liveness check of a call or goal in progress: the server is in the ROS
        graph (``ready``) and, with ``peer_alive``, the user's own check says it lives
        (a heartbeat, a process: what does not wait for the DDS lease)."""
        alive = self._peer_alive
        if alive is None:
            return Liveness(ready, period, start)

        def check() -> bool:
            try:
                lives = bool(alive())
            except Exception as exc:
                raise StateAbort(f"peer_alive raised {type(exc).__name__}: {exc}") from exc
            return lives and ready()

        return Liveness(check, period, start)

    def _wait_for_peer(
        self, ready: Callable[[], bool], what: str, timeout: float | None
    ) -> str | None:
        """Wait for the server (``what``, for the message) until ``ready()``: None once
        it is there, else the outcome to return (``preempted``, or ``aborted`` after
        ``timeout`` seconds: ``server_wait_timeout``)."""
        if self.preempt_requested():
            return self._preempted()
        waited = self._wait_until(ready, timeout)
        if waited == "preempted":
            return self._preempted()
        if waited == "timeout":
            return self._fail(f"{what} did not appear within {timeout} s (server_wait_timeout)")
        return None

    #: What the state talks to (service, action, topic name), for error messages.
    _ros_name: str = ""

    def _callback(
        self,
        what: str,
        cb: Callable[..., Any] | None,
        args: Sequence[Any] | None,
        kwargs: Mapping[str, Any] | None,
    ) -> Bound | None:
        """Check a user callback, adopt its declared interface, bind its extra arguments."""
        if cb is None:
            return None
        if not callable(cb):
            raise smach.InvalidStateError(
                f"{type(self).__name__} {self._ros_name!r}: {what} must be callable, got {cb!r}"
            )
        self._adopt_interface(cb)
        return cb, tuple(args or ()), dict(kwargs or {})

    def _declare_keys(
        self,
        input_keys: Iterable[str] | None,
        output_keys: Iterable[str] | None,
        sent: tuple[str | None, Sequence[str]],
        received: tuple[str | None, Sequence[str]],
    ) -> None:
        """Register the userdata keys: ``input_keys`` plus the key and slots the sent
        message (request, goal) is read from, ``output_keys`` plus those the received
        one (response, result) is written to."""
        for register, given, (key, slots) in (
            (self.register_input_keys, input_keys, sent),
            (self.register_output_keys, output_keys, received),
        ):
            register([*(given or ()), *slots, *([] if key is None else [key])])

    def _check_slots(self, what: str, slots: Sequence[str], message_type: Any) -> None:
        """Construction error unless every slot is a field of ``message_type``."""
        fields = message_type.get_fields_and_field_types()
        unknown = [slot for slot in slots if slot not in fields]
        if unknown:
            raise smach.InvalidStateError(
                f"{type(self).__name__} {self._ros_name!r}: {what} {unknown} are not fields "
                f"of {message_type.__name__}; fields: {', '.join(fields) or 'none'}"
            )

    def _compose(
        self,
        ud: smach.UserData,
        what: str,
        message: Any,
        key: str | None,
        slots: Sequence[str],
        callback: Bound | None,
        message_type: Any,
    ) -> Any:
        """The message to send (a goal or request): ``message``, or ``ud[key]``, with
        ``slots`` set from the userdata, then what ``callback`` returns if anything.
        :class:`StateAbort` when any of that fails or the result is not a
        ``message_type``."""
        if key is not None:
            if key not in ud:
                raise StateAbort(f"{what} key {key!r} is not in the userdata")
            message = ud[key]
        for slot in slots:
            if slot not in ud:
                raise StateAbort(f"{what} slot {slot!r} is not in the userdata")
            try:
                setattr(message, slot, ud[slot])
            except (AttributeError, TypeError, ValueError, AssertionError) as exc:
                raise StateAbort(f"{what} slot {slot!r}: {type(exc).__name__}: {exc}") from exc
        replaced = self._call_back(f"{what}_cb", callback, ud, message)
        if replaced is not None:
            message = replaced
        if not isinstance(message, message_type):
            raise StateAbort(
                f"the {what} is a {type(message).__name__}, not a {message_type.__name__}"
            )
        return message

    def _call_back(self, what: str, callback: Bound | None, *values: Any) -> Any:
        """``callback(*values, *args, **kwargs)``, or None without a callback;
        :class:`StateAbort` if it raises."""
        if callback is None:
            return None
        cb, args, kwargs = callback
        try:
            return cb(*values, *args, **kwargs)
        except Exception as exc:
            raise StateAbort(f"{what} raised {type(exc).__name__}: {exc}") from exc

    def _chosen_outcome(self, what: str, callback: Bound | None, *values: Any) -> str | None:
        """The outcome a ``response_cb``/``result_cb`` chose (None: it did not);
        :class:`StateAbort` if it raises or returns an unregistered outcome."""
        chosen = self._call_back(what, callback, *values)
        if chosen is not None and chosen not in self.get_registered_outcomes():
            raise StateAbort(
                f"{what} returned {chosen!r}; registered outcomes: "
                f"{', '.join(self.get_registered_outcomes())}"
            )
        return None if chosen is None else str(chosen)

    @staticmethod
    def _store(ud: smach.UserData, value: Any, key: str | None, slots: Sequence[str]) -> None:
        """Write ``value`` (a response or result) to ``ud[key]`` and its ``slots``."""
        if key is not None:
            ud[key] = value
        for slot in slots:
            ud[slot] = getattr(value, slot)

    def _guarded(self, run: Callable[[], str]) -> str:
        """``run()`` (a state's execution), with ``aborted`` and the reason logged for
        a :class:`StateAbort`, and for the ROS entities it uses being destroyed under
        it (rclpy shut down, or the helper node destroyed, while the state was still
        waiting) instead of an ``InvalidHandle`` raised in the executing thread."""
        try:
            return run()
        except StateAbort as exc:
            return self._fail(str(exc))
        except (InvalidHandle, RCLError) as exc:
            # InvalidHandle: an entity was destroyed. RCLError: a real failure, unless
            # the context is gone (then every rcl call fails the same way).
            if isinstance(exc, RCLError) and self._context_ok():
                raise
            return self._fail(
                f"its ROS node was destroyed (rclpy shut down?) while it ran: "
                f"{type(exc).__name__}: {exc}"
            )

    def _context_ok(self) -> bool:
        try:
            return bool(self._node.context.ok())
        except Exception:
            return False

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
