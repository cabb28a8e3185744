"""The rclpy names smach.ros uses, for code built beside it (public).

``from smach.ros.rclpy_api import rclpy, MultiThreadedExecutor`` gives the same rclpy
objects smach.ros itself uses, loaded once in one place: rclpy's message generator
imports ``lark``, whose one known ``DeprecationWarning`` (``sre_parse``) is silenced
while it loads, so programs and test suites running with warnings as errors can
load message types. Without the ``ros`` extra, importing this module raises
:class:`~smach.exceptions.MissingExtraError` (a :class:`ModuleNotFoundError`) naming
the extra to install; ``pytest.importorskip("smach.ros.rclpy_api")`` skips on it.

Every name is typed ``Any``: rclpy ships partial type hints and the message packages
none, and smach type-checks the same with or without the extra. ``ActionClient`` is
rclpy's with one fix (it can be created while its node is being spun, as smach's
helper node always is); the others are rclpy's own.
"""

from __future__ import annotations

from smach.ros._api import (
    ActionClient,
    ActionServer,
    CancelResponse,
    DurabilityPolicy,
    ExternalShutdownException,
    GoalResponse,
    GoalStatus,
    MultiThreadedExecutor,
    QoSProfile,
    ReentrantCallbackGroup,
    ReliabilityPolicy,
    SingleThreadedExecutor,
    StringMsg,
    rclpy,
)

__all__ = [
    "ActionClient",
    "ActionServer",
    "CancelResponse",
    "DurabilityPolicy",
    "ExternalShutdownException",
    "GoalResponse",
    "GoalStatus",
    "MultiThreadedExecutor",
    "QoSProfile",
    "ReentrantCallbackGroup",
    "ReliabilityPolicy",
    "SingleThreadedExecutor",
    "StringMsg",
    "rclpy",
]
