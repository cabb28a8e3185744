"""smach.ros: SMACH states and servers for ROS 2 (rclpy).

The only part of ``smach`` that imports rclpy (install the ``ros`` extra), and only
when one of its names is first used: ``import smach.ros`` (and ``import smach_ros``)
works without rclpy, and using a name then raises :class:`ModuleNotFoundError`
naming the extra to install. The states accept the ROS 2 signature (an rclpy node
first) and the ROS 1 one (no node: :func:`default_node`). They fix the originals'
hangs: every wait is bounded and preemptable, preempt requests return at once, and
the ROS callbacks are served by smach's own executor thread, so nothing depends on
how (or whether) your node is spun. See docs/ros.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from smach.ros.action_server_wrapper import ActionServerWrapper
    from smach.ros.condition_state import ConditionState
    from smach.ros.executor import SmachExecutor
    from smach.ros.introspection import IntrospectionClient, IntrospectionServer
    from smach.ros.monitor_state import MonitorState
    from smach.ros.preempt_handler import set_preempt_handler
    from smach.ros.ros_state import RosState, SmachNode
    from smach.ros.service_state import ServiceState
    from smach.ros.shared_node import default_node, shutdown_default_node
    from smach.ros.simple_action_state import SimpleActionState

#: Public name -> the submodule defining it (imported, with rclpy, on first use).
LAZY_NAMES = {
    "ActionServerWrapper": "action_server_wrapper",
    "ConditionState": "condition_state",
    "IntrospectionClient": "introspection",
    "IntrospectionServer": "introspection",
    "MonitorState": "monitor_state",
    "RosState": "ros_state",
    "ServiceState": "service_state",
    "SimpleActionState": "simple_action_state",
    "SmachExecutor": "executor",
    "SmachNode": "ros_state",
    "default_node": "shared_node",
    "set_preempt_handler": "preempt_handler",
    "shutdown_default_node": "shared_node",
}

__all__ = [
    "ActionServerWrapper",
    "ConditionState",
    "IntrospectionClient",
    "IntrospectionServer",
    "MonitorState",
    "RosState",
    "ServiceState",
    "SimpleActionState",
    "SmachExecutor",
    "SmachNode",
    "default_node",
    "set_preempt_handler",
    "shutdown_default_node",
]


def __getattr__(name: str) -> Any:
    module = LAZY_NAMES.get(name)
    if module is None:
        raise AttributeError(f"module 'smach.ros' has no attribute {name!r}")
    # Raises ModuleNotFoundError naming the ``ros`` extra when rclpy is missing.
    value = getattr(importlib.import_module(f"smach.ros.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *LAZY_NAMES])
