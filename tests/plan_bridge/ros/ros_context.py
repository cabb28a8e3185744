"""rclpy nodes in a context of their own, for a test, shut down after it; a call of a
project service that answers in text (``test_msgs/BasicTypes``, ``std_srvs/Trigger``)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
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


def call_text_service(
    node: Any,
    name: str,
    kind: Any,
    text: str = "",
    flag: bool = False,
    *,
    timeout: float,
    wait: Callable[[Any], object],
) -> tuple[bool, str]:
    """Call service ``name`` of type ``kind`` from ``node``: a ``BasicTypes`` request
    carries ``text`` and ``flag``; ``wait(future)`` waits for the answer (a spun node's
    caller polls, an unspun one spins). (ok, text) of the reply: ``BasicTypes``'
    ``bool_value`` and ``string_value``, ``Trigger``'s ``success`` and ``message``."""
    client = node.create_client(kind, name)
    try:
        assert client.wait_for_service(timeout_sec=timeout), f"no service {name}"
        request = kind.Request()
        if hasattr(request, "string_value"):
            request.string_value, request.bool_value = text, flag
        future = client.call_async(request)
        wait(future)
        assert future.done(), f"{name} did not answer"
        reply = future.result()
    finally:
        node.destroy_client(client)
    if hasattr(reply, "message"):
        return reply.success, reply.message
    return reply.bool_value, reply.string_value
