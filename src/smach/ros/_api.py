"""The rclpy names smach.ros uses, imported in one place.

Everything is typed ``Any`` on purpose: rclpy ships partial type hints, the message
packages none, and smach must type-check the same whether or not the ``ros`` extra
is installed. Importing this module raises :class:`ImportError` with the install
hint when rclpy is missing.

rclpy's message generator imports ``lark`` 0.12, which imports the deprecated
``sre_parse`` module; that one known :class:`DeprecationWarning` is silenced here,
once, so that programs (and test suites) running with warnings as errors can load
message types. Every other warning is left alone.
"""

from __future__ import annotations

import importlib
import threading
import warnings
from typing import Any

from smach.exceptions import MissingExtraError

__all__ = [
    "ActionClient",
    "ActionServer",
    "CancelResponse",
    "DurabilityPolicy",
    "GoalResponse",
    "GoalStatus",
    "InvalidHandle",
    "MultiThreadedExecutor",
    "QoSProfile",
    "RCLError",
    "ReentrantCallbackGroup",
    "StringMsg",
    "rclpy",
]


def _load(name: str) -> Any:
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        # ModuleNotFoundError: what is missing is a package (pytest.importorskip and
        # callers checking for an optional extra expect this type).
        raise MissingExtraError(
            f"smach.ros needs rclpy and the ROS 2 message packages ({name} is missing); "
            'install them with: pip install "smach-planner[ros]"'
        ) from exc


with warnings.catch_warnings():
    warnings.filterwarnings(
        "ignore",
        message=r"module 'sre_(parse|constants)' is deprecated",
        category=DeprecationWarning,
    )
    rclpy: Any = _load("rclpy")
    # Loaded lazily by rclpy the first time a message type is registered.
    _load("rosidl_generator_py")

_action: Any = _load("rclpy.action")
_executors: Any = _load("rclpy.executors")
_callback_groups: Any = _load("rclpy.callback_groups")
_qos: Any = _load("rclpy.qos")
_events: Any = _load("rclpy.event_handler")


class ActionClient(_action.ActionClient):  # type: ignore[misc]
    """rclpy's ActionClient, safe to create while its node is being spun.

    rclpy 9 registers the client with its node before creating the lock that its
    executor callbacks take, so an executor thread spinning the node at that moment
    fails with ``AttributeError: _lock``. smach's helper node is always spinning:
    the lock is created first here (rclpy then replaces it before any goal exists).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._lock = threading.Lock()
        super().__init__(*args, **kwargs)


ActionServer: Any = _action.ActionServer
CancelResponse: Any = _action.CancelResponse
GoalResponse: Any = _action.GoalResponse
MultiThreadedExecutor: Any = _executors.MultiThreadedExecutor
SingleThreadedExecutor: Any = _executors.SingleThreadedExecutor
ExternalShutdownException: Any = _executors.ExternalShutdownException
ReentrantCallbackGroup: Any = _callback_groups.ReentrantCallbackGroup
QoSProfile: Any = _qos.QoSProfile
DurabilityPolicy: Any = _qos.DurabilityPolicy
ReliabilityPolicy: Any = _qos.ReliabilityPolicy
GoalStatus: Any = _load("action_msgs.msg").GoalStatus
StringMsg: Any = _load("std_msgs.msg").String
Node: Any = _load("rclpy.node").Node
SubscriptionEventCallbacks: Any = _events.SubscriptionEventCallbacks
PublisherEventCallbacks: Any = _events.PublisherEventCallbacks
_implementation: Any = _load("rclpy.impl.implementation_singleton").rclpy_implementation
#: Raised by rclpy when a destroyed (or being destroyed) node, client... is used.
InvalidHandle: Any = _implementation.InvalidHandle
#: Raised by rcl calls, e.g. on an entity whose context was shut down.
RCLError: Any = _implementation.RCLError
