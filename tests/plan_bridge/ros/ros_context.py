"""rclpy nodes in a context of their own, for a test, shut down after it."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from smach.ros.executor import SmachExecutor
from smach.ros.rclpy_api import rclpy


@contextmanager
def nodes_in_own_context(*names: str) -> Iterator[tuple[Any, ...]]:
    """Nodes ``names`` in one new context; afterwards smach's helper executor of that
    context stops, the nodes are destroyed (last first) and the context shut down."""
    context = rclpy.Context()
    rclpy.init(context=context)
    nodes = tuple(rclpy.create_node(name, context=context) for name in names)
    try:
        yield nodes
    finally:
        helper = SmachExecutor._instances.get(id(context))
        if helper is not None:
            helper.shutdown()
        for node in reversed(nodes):
            node.destroy_node()
        rclpy.shutdown(context=context)
