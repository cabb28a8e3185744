"""Orders over ROS 2: send, cancel and list the orders of a running mission.

``OrderServices(node, desk)`` (or ``RobotConnection.serve_orders``) offers under
``NAME`` (default ``orders``, resolved against ``node``'s namespace), for the
:class:`~plan_bridge.orders.requests.OrderDesk` of a mission of orders:

==================  ============  ===========================================================
name                type          request -> response
==================  ============  ===========================================================
``submit``          BasicTypes    ``string_value``: the goal (``"(At gear tool_rack_shelf)"``
                                  or a goal's name), or a JSON object ``{"goal": ..., "id":
                                  ..., "priority": 2, "within": 300}``; ``bool_value`` true
                                  and the order's id, or false and the refusal
``cancel``          BasicTypes    ``string_value``: the order's id (or ``{"id": ...,
                                  "reason": ...}``); true and the order as JSON, or false
                                  and the refusal
``list``            Trigger       ``message``: every order as JSON (a list of the
                                  ``OrderState.to_json()`` of each, in arrival order)
``status``          String topic  one JSON message per status change (reliable, transient
                                  local, the last :data:`STATUS_DEPTH` kept for late joiners)
==================  ============  ===========================================================

``BasicTypes`` is ``test_msgs/srv/BasicTypes``, ``Trigger`` ``std_srvs/srv/Trigger`` and
``String`` ``std_msgs/msg/String``, as for the knowledge base
(:mod:`plan_bridge.ros.knowledge_services`): no message package of our own. A status
message is the order's JSON (``id``, ``goal``, ``status``, ``robots``, ``reason``,
``arrived``, ``latency`` ...) with ``changed``: the mission's clock at the change.
Every change of every order is published once, in the order it happened for that
order. The services live on smach's helper node and its executor thread (nothing needs
to spin for them); the desk and its book are thread-safe.
"""

from __future__ import annotations

import importlib
import json
import threading
from collections.abc import Callable
from typing import Any

from plan_bridge.orders.book import OrderBookError
from plan_bridge.orders.order import OrderState
from plan_bridge.orders.requests import OrderDesk

__all__ = ["STATUS_DEPTH", "OrderServices"]

#: The longest request text a service accepts (characters).
MAX_REQUEST = 64 * 1024
#: Status messages the topic keeps for a subscriber that joins late.
STATUS_DEPTH = 1000


class OrderServices:
    """The order services and status topic of one node (see the module documentation)."""

    def __init__(self, node: Any, desk: OrderDesk, *, name: str = "orders") -> None:
        # smach.ros.rclpy_api loads rclpy with its one known warning silenced.
        from smach.ros.executor import SmachExecutor, publisher_events
        from smach.ros.rclpy_api import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        basic = importlib.import_module("test_msgs.srv").BasicTypes
        trigger = importlib.import_module("std_srvs.srv").Trigger
        self._string = importlib.import_module("std_msgs.msg").String
        self.desk = desk
        self._helper = SmachExecutor.for_node(node)
        helper = self._helper.node
        base = node.resolve_service_name(name).rstrip("/")
        #: Service or topic (``submit``, ``status``) -> its full ROS name.
        self.names = {key: f"{base}/{key}" for key in ("submit", "cancel", "list", "status")}
        group = self._helper.callback_group
        self._services = [
            helper.create_service(
                basic, self.names["submit"], self._basic(self._submit), callback_group=group
            ),
            helper.create_service(
                basic, self.names["cancel"], self._basic(self._cancel), callback_group=group
            ),
            helper.create_service(trigger, self.names["list"], self._list, callback_group=group),
        ]
        qos = QoSProfile(
            depth=STATUS_DEPTH,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self._publisher = helper.create_publisher(
            self._string,
            self.names["status"],
            qos,
            event_callbacks=publisher_events(self.names["status"]),
        )
        # How many entries of each order's history are published (each change once).
        self._published: dict[str, int] = {}
        self._publish_lock = threading.Lock()
        desk.book.add_listener(self._changed)

    def close(self) -> None:
        """Remove the services and the topic (once; a second call does nothing)."""
        self.desk.book.remove_listener(self._changed)
        services, self._services = self._services, []
        if not services or not self._helper.alive:
            return  # closed already, or the node is gone with them
        for service in services:
            self._helper.node.destroy_service(service)
        self._helper.node.destroy_publisher(self._publisher)

    # -- callbacks (smach's executor threads) ------------------------------------------------
    def _basic(self, work: Callable[[str], str]) -> Callable[[Any, Any], Any]:
        def callback(request: Any, response: Any) -> Any:
            response.bool_value, response.string_value = _answer(
                lambda: work(str(request.string_value))
            )
            return response

        return callback

    def _list(self, request: Any, response: Any) -> Any:
        response.success, response.message = _answer(
            lambda: json.dumps(self.desk.listing({}), default=str)
        )
        return response

    def _submit(self, text: str) -> str:
        body = _body(text, "goal")
        reply = self.desk.order({**body, "source": "ros"})
        return str(reply["id"]) if isinstance(reply, dict) else str(reply)

    def _cancel(self, text: str) -> str:
        body = _body(text, "id")
        return json.dumps(self.desk.cancel({**body, "source": "ros"}), default=str)

    # -- the status topic ---------------------------------------------------------------------
    def _changed(self, state: OrderState) -> None:
        """Publish every change of ``state`` not published yet, oldest first (a listener
        may be called after a later change of the same order, from another thread)."""
        with self._publish_lock:
            history = list(state.history)
            done = self._published.get(state.id, 0)
            self._published[state.id] = max(done, len(history))
            data = state.to_json()
            for changed, status in history[done:]:
                message = self._string()
                message.data = json.dumps(
                    {**data, "status": status, "changed": round(changed, 3)}, default=str
                )
                self._publisher.publish(message)


def _body(text: str, key: str) -> dict[str, Any]:
    """A request's text: a JSON object, or the plain value of ``key``."""
    if len(text) > MAX_REQUEST:
        raise OrderBookError(f"a request is at most {MAX_REQUEST} characters")
    if not text.lstrip().startswith("{"):
        return {key: text}
    try:
        body = json.loads(text)
    except json.JSONDecodeError as exc:
        raise OrderBookError(f"the request is not JSON: {exc}") from None
    if not isinstance(body, dict):
        raise OrderBookError(f'expected a JSON object like {{"{key}": ...}}')
    return body


def _answer(work: Callable[[], str]) -> tuple[bool, str]:
    try:
        return True, work()
    except ValueError as exc:  # OrderBookError: the refusal, saying why
        return False, str(exc)
    except Exception as exc:  # a bug must not stop the executor thread
        return False, f"internal error: {type(exc).__name__}: {exc}"
