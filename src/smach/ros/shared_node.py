"""The default node: what ROS states use when ported code passes none.

ROS 1 smach_ros states took no node (``SimpleActionState('fib', FibonacciAction)``):
rospy had one implicit node per process, made by ``rospy.init_node``. The ROS 2
port put an rclpy node first in every constructor. Both forms are accepted here.
When a state gets no node (the ROS 1 form, or ``node=None``), it uses the
*default node*:

* one per process, named ``smach_ros_<pid>``, created on first use;
* in rclpy's default context if the program has called ``rclpy.init()``; if not,
  in a context smach creates and initialises then (not the default one, so the
  program may still call ``rclpy.init()`` later; ``rclpy.ok()`` tells about the
  default context only);
* spun by smach's helper executor (:mod:`smach.ros.executor`), so its parameter
  services answer without you spinning anything;
* shut down cleanly: forgotten when its context shuts down (``rclpy.shutdown()``);
  destroyed by :func:`shutdown_default_node` and at interpreter exit, which also
  shut down the context smach initialised (a context you initialised stays yours).

Names given to states without a node resolve against the default node, i.e. the
root namespace unless ``--ros-args`` remapping rules say otherwise.
"""

from __future__ import annotations

import atexit
import functools
import os
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from smach.ros._api import rclpy

__all__ = ["default_node", "ensure_init", "is_node", "node_optional", "shutdown_default_node"]

_lock = threading.RLock()
_node: Any = None
_own_context: Any = None
#: Contexts smach initialised itself (ids), to shut down at exit.
_initialised: dict[int, Any] = {}

F = TypeVar("F", bound=Callable[..., None])


def is_node(value: object) -> bool:
    """True for an rclpy ``Node`` (anything with a context that resolves topic names)."""
    return hasattr(value, "resolve_topic_name") and hasattr(value, "context")


def ensure_init(context: Any = None) -> Any:
    """An initialised rclpy context: ``context`` (initialised if needed), else a default.

    Without ``context``: rclpy's default context if the program has called
    ``rclpy.init()``, else a context of smach's own, initialised here. ROS 1
    scripts called ``rospy.init_node`` themselves; ported scripts often call
    ``rclpy.init()`` late or not at all. smach does not initialise the *default*
    context itself, so a later ``rclpy.init()`` in the program still works.
    """
    global _own_context
    with _lock:
        if context is not None:
            if not context.ok():
                try:
                    rclpy.init(context=context)
                except RuntimeError as exc:
                    raise RuntimeError(
                        f"cannot initialise the given rclpy context (was it shut down? "
                        f"create a new rclpy.Context): {exc}"
                    ) from exc
                _initialised[id(context)] = context
            return context
        default = rclpy.get_default_context()
        if default.ok():
            return default
        if _own_context is None or not _own_context.ok():
            _own_context = rclpy.Context()
            rclpy.init(context=_own_context)
            _initialised[id(_own_context)] = _own_context
        return _own_context


def default_node() -> Any:
    """The process's default node (created, and rclpy initialised, on first use)."""
    global _node
    with _lock:
        node = _node
        if node is not None and node.context.ok():
            return node
        context = ensure_init()
        from smach.ros.executor import SmachExecutor

        node = rclpy.create_node(f"smach_ros_{os.getpid()}", context=context)
        SmachExecutor.for_context(context).executor.add_node(node)
        _node = node
        # Called with the context's lock held: only forget the node here.
        context.on_shutdown(_forget)
        return node


def _forget() -> None:
    global _node
    _node = None


def shutdown_default_node() -> None:
    """Destroy the default node; if smach called ``rclpy.init()``, shut rclpy down too.

    Runs at interpreter exit. After it, the next state without a node starts over
    (initialising rclpy again if needed).
    """
    global _node
    from smach.ros.executor import SmachExecutor

    with _lock:
        node, _node = _node, None
        contexts = list(_initialised.values())
        _initialised.clear()
        if node is not None and node.context.ok():
            helper = SmachExecutor._instances.get(id(node.context))
            if helper is not None:
                helper.executor.remove_node(node)
            node.destroy_node()
        for context in contexts:
            helper = SmachExecutor._instances.get(id(context))
            if helper is not None:
                helper.shutdown(timeout=1.0)
            rclpy.try_shutdown(context=context)


atexit.register(shutdown_default_node)


def node_optional(init: F) -> F:
    """Let a ROS state's ``__init__(self, node, ...)`` also be called without the node.

    ``State(node, name, ...)`` is the ROS 2 form. ``State(name, ...)`` (the first
    positional argument is not a node: the ROS 1 form), ``State(node=None, ...)`` or
    ``State(None, name, ...)`` use :func:`default_node`. The instance attribute
    ``_default_node_used`` tells ``__init__`` which form it got.
    """

    @functools.wraps(init)
    def wrapper(self: Any, *args: Any, **kwargs: Any) -> None:
        if "node" in kwargs:
            used = kwargs["node"] is None
            if used:
                kwargs["node"] = default_node()
        elif args and is_node(args[0]):
            used = False
        elif args and args[0] is None:
            used = True
            args = (default_node(), *args[1:])
        else:
            used = True
            args = (default_node(), *args)
        self._default_node_used = used
        init(self, *args, **kwargs)

    return wrapper  # type: ignore[return-value]
