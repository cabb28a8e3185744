"""Another process's view of a mission's orders over ROS 2: the order services' client
and the status topic's listener, in an rclpy context of its own."""

from __future__ import annotations

import json
import threading
from typing import Any

from ros_context import call_text_service
from std_msgs.msg import String
from std_srvs.srv import Trigger
from test_msgs.srv import BasicTypes

from plan_bridge.ros.order_services import STATUS_DEPTH
from smach.ros.rclpy_api import DurabilityPolicy, QoSProfile, ReliabilityPolicy, rclpy
from waiting import wait_until

__all__ = ["Operator"]


class Operator:
    """Another process's view: its own context and node, spun in a thread; calls the
    order services and collects the status topic."""

    def __init__(self, base: str) -> None:
        self.base = base
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("operator", context=self.context)
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.status: list[dict[str, Any]] = []
        qos = QoSProfile(
            depth=STATUS_DEPTH,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.node.create_subscription(
            String, f"{base}/status", lambda m: self.status.append(json.loads(m.data)), qos
        )
        self.spinner = threading.Thread(target=self.executor.spin, daemon=True)
        self.spinner.start()

    def call(self, service: str, text: str = "") -> tuple[bool, str]:
        kind = Trigger if service == "list" else BasicTypes
        return call_text_service(
            self.node,
            f"{self.base}/{service}",
            kind,
            text,
            timeout=20,
            wait=lambda future: wait_until(future.done, 20),
        )

    def statuses(self, order: str) -> list[str]:
        return [m["status"] for m in list(self.status) if m["id"] == order]

    def close(self) -> None:
        self.executor.shutdown()
        self.spinner.join(10)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
