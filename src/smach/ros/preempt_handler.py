"""``set_preempt_handler``: preempt a state machine when ROS shuts down."""

from __future__ import annotations

from typing import Any

import smach
from smach.ros._api import rclpy

__all__ = ["set_preempt_handler"]


def set_preempt_handler(sc: smach.State, context: Any = None) -> None:
    """Call ``sc.request_preempt()`` when the rclpy context shuts down.

    The original then polled ``sc.is_running()`` once a second inside the shutdown
    hook; here the hook returns at once (``request_preempt`` does not block), so
    ``rclpy.shutdown()`` is not held up. Wait for your ``execute()`` thread yourself.
    """
    if context is None:
        context = rclpy.get_default_context()

    def handler() -> None:
        smach.loginfo("ROS shutdown: preempting the state machine")
        sc.request_preempt()

    context.on_shutdown(handler)
