"""Who serves the ROS callbacks of smach's ROS states: one helper node per context.

A SMACH state blocks in ``execute()`` until its action server, service or topic
answers, and those answers arrive as rclpy callbacks, which only run while some
executor spins the node that owns the client. The original smach_ros relied on
the user spinning *their* node in another thread; if they did not, or if they ran
the state machine from inside a callback of a single-threaded executor (a timer,
a service, an action server's execute callback), the state waited for a callback
that its own thread was supposed to run: a deadlock (smach_ros issue #128).

Here every ROS entity smach creates (action and service clients, subscriptions,
action servers, introspection publishers) lives on a *helper node* owned by
smach, spun by a private :class:`MultiThreadedExecutor` in a daemon thread. There
is one helper per rclpy context, created on first use and destroyed with the
context (``rclpy.shutdown()``). The user's node is still the first argument of
every state: names are resolved against it (namespace, ``~`` and remapping
rules), and its logger is used. So states work whether the user's node is spun
by a single-threaded executor, a multi-threaded one, or not at all, and
``execute()`` may be called from any thread, including a callback of the user's
own executor.

Callbacks of the helper do nothing but store what arrived and wake the waiting
state; user callbacks (``goal_cb``, ``result_cb``, ``feedback_cb``, ``cond_cb``,
``response_cb``) run in the thread that executes the state, so userdata is only
touched by that thread. The exception is :class:`~smach.ros.ActionServerWrapper`,
whose goals run the wrapped container on an executor thread (that is what an
action server's execute callback is); the executor has enough threads for that.
"""

from __future__ import annotations

import atexit
import itertools
import os
import threading
import time
from typing import Any

import smach
from smach.ros._api import (
    ExternalShutdownException,
    MultiThreadedExecutor,
    PublisherEventCallbacks,
    ReentrantCallbackGroup,
    SubscriptionEventCallbacks,
    rclpy,
)

__all__ = [
    "SmachExecutor",
    "publisher_events",
    "seconds",
    "subscription_events",
    "wait_for_callbacks",
]

#: Executor threads: callbacks are short, except action-server goals (one per wrapper).
EXECUTOR_THREADS = 8

_counter = itertools.count(1)


def seconds(value: Any, name: str, *, allow_none: bool = True) -> float | None:
    """A timeout given as float seconds or an rclpy ``Duration``, in seconds.

    ``None`` means "no limit" where allowed. Negative values are refused.
    """
    if value is None:
        if allow_none:
            return None
        raise ValueError(f"{name} must be a number of seconds or an rclpy Duration, not None")
    nanoseconds = getattr(value, "nanoseconds", None)
    if isinstance(nanoseconds, int):
        result = nanoseconds / 1e9
    elif isinstance(value, int | float) and not isinstance(value, bool):
        result = float(value)
    else:
        raise TypeError(
            f"{name} must be a number of seconds or an rclpy Duration, got {value!r} "
            f"({type(value).__name__})"
        )
    if result < 0:
        raise ValueError(f"{name} must not be negative, got {result} s")
    return result


class SmachExecutor:
    """The helper node and the executor thread that serve smach's ROS entities."""

    _lock = threading.Lock()
    _instances: dict[int, SmachExecutor] = {}

    def __init__(self, context: Any) -> None:
        self.context = context
        self.node: Any = rclpy.create_node(
            f"_smach_{os.getpid()}_{next(_counter)}",
            context=context,
            start_parameter_services=False,
        )
        #: Every entity smach creates joins this group, so one slow callback (an
        #: action-server goal running a container) never holds up the others.
        self.callback_group: Any = ReentrantCallbackGroup()
        self.executor: Any = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS, context=context)
        self.executor.add_node(self.node)
        self._alive = True
        self._thread = threading.Thread(
            target=self._spin, name=f"smach-ros-executor-{self.node.get_name()}", daemon=True
        )
        self._thread.start()
        # Called with the context's lock held: only flip a flag here.
        context.on_shutdown(self._on_shutdown)

    @classmethod
    def for_node(cls, node: Any) -> SmachExecutor:
        """The helper serving ``node``'s context (created on first use)."""
        return cls.for_context(node.context)

    @classmethod
    def for_context(cls, context: Any = None) -> SmachExecutor:
        if context is None:
            context = rclpy.get_default_context()
        with cls._lock:
            instance = cls._instances.get(id(context))
            if instance is None or not instance.alive or instance.context is not context:
                if not context.ok():
                    raise RuntimeError(
                        "the rclpy context is not initialised (call rclpy.init() first) "
                        "or has been shut down"
                    )
                instance = cls(context)
                cls._instances[id(context)] = instance
            return instance

    @property
    def alive(self) -> bool:
        return self._alive and self._thread.is_alive()

    def _on_shutdown(self) -> None:
        self._alive = False

    def _spin(self) -> None:
        try:
            while self._alive and self.context.ok():
                try:
                    self.executor.spin_once(timeout_sec=0.2)
                except ExternalShutdownException:
                    break
                except Exception as exc:
                    if not self.context.ok():
                        break  # the context went away under us
                    # A failing callback must not take every smach state down with it.
                    smach.logerr(f"smach ROS executor: a callback raised {exc!r}")
        finally:
            self._alive = False

    def shutdown(self, timeout: float = 2.0) -> bool:
        """Stop the executor thread and destroy the helper node (tests, clean exits).

        The executor and the node are destroyed only once no callback runs on them any
        more: destroying them under a running callback (an action-server goal, a
        state's client call) makes that callback fail in its thread with
        ``InvalidHandle``. If the thread or a callback still runs after ``timeout``
        seconds, both are left to the context's shutdown (``rclpy.shutdown``) and
        False is returned.
        """
        self._alive = False
        deadline = time.monotonic() + timeout
        self._thread.join(timeout)
        with SmachExecutor._lock:
            if SmachExecutor._instances.get(id(self.context)) is self:
                del SmachExecutor._instances[id(self.context)]
        if self._thread.is_alive() or not wait_for_callbacks(
            self.executor, max(0.0, deadline - time.monotonic())
        ):
            smach.logwarn(
                f"smach ROS executor: a callback still runs after {timeout} s; the helper "
                "node is left to rclpy.shutdown()"
            )
            return False
        self.executor.shutdown(timeout_sec=0)
        if self.context.ok():
            self.node.destroy_node()
        return True


def wait_for_callbacks(executor: Any, timeout: float) -> bool:
    """Wait until no callback that ``executor`` started runs any more (call it once
    nothing spins the executor): True if so within ``timeout`` seconds.

    rclpy's ``Executor.shutdown(timeout_sec)`` (rclpy 7.1 and 9.1 alike) does not
    wait for them, although it says it does, and destroys the executor's guard
    condition, which a callback finishing afterwards triggers: ``InvalidHandle`` in
    a thread of the executor's pool. A :class:`MultiThreadedExecutor` keeps the
    callbacks it started in ``_futures`` in both versions; a single-threaded one
    runs them in the spinning thread, so there is nothing to wait for.
    """
    deadline = time.monotonic() + timeout
    while any(not task.done() for task in list(getattr(executor, "_futures", ()))):
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.01)
    return True


def _stop_all() -> None:
    # Let executor threads leave rclpy before the interpreter tears it down (a
    # daemon thread inside rcl at exit aborts the process). Also registered to run
    # when the main thread ends, before concurrent.futures refuses new work: a
    # message arriving then would make the spinning thread fail loudly.
    with SmachExecutor._lock:
        instances = list(SmachExecutor._instances.values())
    for instance in instances:
        instance._alive = False
    for instance in instances:
        instance._thread.join(1.0)


atexit.register(_stop_all)
# Private but stable since Python 3.9; runs in reverse order of registration, so
# before concurrent.futures' own hook (registered when rclpy imported it).
_register_thread_exit = getattr(threading, "_register_atexit", None)
if _register_thread_exit is not None:
    _register_thread_exit(_stop_all)


def subscription_events(topic: str) -> Any:
    """Event callbacks for smach's subscriptions.

    rclpy's default handlers report QoS or type mismatches through a deprecated
    logger method, which raises under ``-W error``; these report through smach's
    loggers instead.
    """
    return SubscriptionEventCallbacks(
        incompatible_qos=lambda event: smach.logwarn(
            f"{topic}: a publisher offers an incompatible QoS; its messages are not received"
        ),
        incompatible_type=lambda event: smach.logwarn(
            f"{topic}: a publisher uses another message type; its messages are not received"
        ),
    )


def publisher_events(topic: str) -> Any:
    """Event callbacks for smach's publishers (see :func:`subscription_events`)."""
    return PublisherEventCallbacks(
        incompatible_qos=lambda event: smach.logwarn(
            f"{topic}: a subscriber requests an incompatible QoS; it receives nothing"
        ),
        incompatible_type=lambda event: smach.logwarn(
            f"{topic}: a subscriber uses another message type; it receives nothing"
        ),
    )


def monotonic_deadline(timeout: float | None) -> float | None:
    """``time.monotonic()`` + ``timeout``, or None for no deadline."""
    return None if timeout is None else time.monotonic() + timeout


def remaining(deadline: float | None) -> float | None:
    return None if deadline is None else deadline - time.monotonic()
