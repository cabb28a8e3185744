"""smach.ros: SMACH states and servers for ROS 2 (rclpy).

The only part of ``smach`` that imports rclpy (install the ``ros`` extra). The
states take the rclpy node first, as in the ROS 2 branch of smach_ros, and fix its
hangs: every wait is bounded and preemptable, preempt requests return at once, and
the ROS callbacks are served by smach's own executor thread, so nothing depends on
how (or whether) your node is spun. See docs/ros.md.
"""

from __future__ import annotations

from smach.ros.action_server_wrapper import ActionServerWrapper
from smach.ros.condition_state import ConditionState
from smach.ros.executor import SmachExecutor
from smach.ros.introspection import IntrospectionClient, IntrospectionServer
from smach.ros.monitor_state import MonitorState
from smach.ros.preempt_handler import set_preempt_handler
from smach.ros.ros_state import RosState, SmachNode
from smach.ros.service_state import ServiceState
from smach.ros.simple_action_state import SimpleActionState

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
    "set_preempt_handler",
]
