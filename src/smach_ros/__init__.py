"""``import smach_ros`` for code ported from ROS: a re-export of :mod:`smach.ros`."""

from __future__ import annotations

from smach.ros import (
    ActionServerWrapper,
    ConditionState,
    IntrospectionClient,
    IntrospectionServer,
    MonitorState,
    RosState,
    ServiceState,
    SimpleActionState,
    SmachExecutor,
    SmachNode,
    set_preempt_handler,
)

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
