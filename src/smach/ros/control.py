"""Runtime control over ROS 2: services next to an introspection server's topics.

``server.serve_control(controller)`` (or ``ControlServices(server, controller)``)
offers, under the server's name (``/NAME/control/...``):

=================  =======================  ==============================================
service            type                     request -> response
=================  =======================  ==============================================
``pause``          ``std_srvs/Trigger``     -> success, message = the control state (JSON)
``resume``         ``std_srvs/Trigger``     same
``step``           ``std_srvs/Trigger``     same
``preempt``        ``std_srvs/Trigger``     preempts the root
``status``         ``std_srvs/Trigger``     the control state, changes nothing
``set_breakpoint`` ``test_msgs/BasicTypes`` ``string_value`` pattern, ``bool_value`` on/off
``force_outcome``  ``test_msgs/BasicTypes`` ``string_value`` outcome, or JSON
                                            ``{"outcome": ..., "path": ...}``
``request``        ``test_msgs/BasicTypes`` ``string_value`` a JSON request as the viewer's
                                            (``{"action": "skip", "apply_effects": true}``)
``change_goal``    ``test_msgs/BasicTypes`` ``string_value`` goal atoms (when the tree is a
                                            plan_bridge mission offering ``goal``)
=================  =======================  ==============================================

``BasicTypes`` replies carry ``bool_value`` (done or refused) and ``string_value`` (the
control state as JSON, or the reason of the refusal). Every action is journaled by
the controller's observers with the source ``ros``. (``BasicTypes`` is the one stock
service type with a string each way; plan_bridge.ros uses it the same way.)

The services live on smach's helper node, served by smach's own executor thread, so
nothing needs to spin for them; their callbacks only call the controller, which never
blocks.
"""

from __future__ import annotations

import importlib
import json
from collections.abc import Callable, Mapping
from typing import Any

from smach.control import Controller
from smach.introspection.control_api import Action, ViewerControls
from smach.ros.executor import SmachExecutor

__all__ = ["ControlServices"]

_TRIGGERS = ("pause", "resume", "step", "preempt", "status")
_MAX_REQUEST = 16 * 1024


class ControlServices:
    """The control services of one tree (see the module documentation)."""

    def __init__(
        self,
        server: Any,
        controller: Controller,
        *,
        actions: Mapping[str, Action] | None = None,
    ) -> None:
        trigger = importlib.import_module("std_srvs.srv").Trigger
        basic = importlib.import_module("test_msgs.srv").BasicTypes
        self.controls = ViewerControls(controller, actions=actions)
        self._helper = SmachExecutor.for_node(server._node)
        node = self._helper.node
        base = server._node.resolve_topic_name(server.server_name) + "/control"
        self.names: dict[str, str] = {}
        self._services: list[Any] = []

        def add(name: str, kind: Any, callback: Callable[[Any, Any], Any]) -> None:
            self.names[name] = f"{base}/{name}"
            self._services.append(node.create_service(kind, f"{base}/{name}", callback))

        for action in _TRIGGERS:
            add(action, trigger, self._trigger(action))
        add("set_breakpoint", basic, self._set_breakpoint)
        add("force_outcome", basic, self._force_outcome)
        add("request", basic, self._request)
        if "goal" in self.controls.actions:
            add("change_goal", basic, self._change_goal)

    def close(self) -> None:
        """Remove the services."""
        node = self._helper.node
        if self._helper.alive:
            for service in self._services:
                node.destroy_service(service)
        self._services = []

    # -- callbacks (smach's executor thread) -------------------------------------------------
    def _status_json(self) -> str:
        return json.dumps(self.controls.controller.status().to_json())

    def _trigger(self, action: str) -> Callable[[Any, Any], Any]:
        def callback(request: Any, response: Any) -> Any:
            if action == "status":
                response.success, response.message = True, self._status_json()
                return response
            ok, text = self._perform({"action": action})
            response.success, response.message = ok, text
            return response

        return callback

    def _perform(self, body: Mapping[str, Any]) -> tuple[bool, str]:
        try:
            reply = self.controls.perform(body, source="ros")
        except ValueError as exc:
            return False, str(exc)
        result = reply.get("result")
        return True, result if isinstance(result, str) else self._status_json()

    def _reply(self, response: Any, body: Mapping[str, Any]) -> Any:
        response.bool_value, response.string_value = self._perform(body)
        return response

    def _set_breakpoint(self, request: Any, response: Any) -> Any:
        action = "add_breakpoint" if request.bool_value else "remove_breakpoint"
        return self._reply(response, {"action": action, "pattern": request.string_value})

    def _force_outcome(self, request: Any, response: Any) -> Any:
        text = request.string_value.strip()
        body: dict[str, Any] = {"action": "force_outcome", "outcome": text}
        if text.startswith("{"):
            parsed = _json_object(text, response)
            if parsed is None:
                return response
            body = {"action": "force_outcome", **parsed}
        return self._reply(response, body)

    def _request(self, request: Any, response: Any) -> Any:
        parsed = _json_object(request.string_value, response)
        if parsed is None:
            return response
        return self._reply(response, parsed)

    def _change_goal(self, request: Any, response: Any) -> Any:
        return self._reply(response, {"action": "goal", "goal": request.string_value})


def _json_object(text: str, response: Any) -> dict[str, Any] | None:
    """``text`` as a JSON object, or None with the refusal written into ``response``."""
    problem = ""
    value: Any = None
    if len(text) > _MAX_REQUEST:
        problem = f"a control request is at most {_MAX_REQUEST} bytes"
    else:
        try:
            value = json.loads(text)
        except json.JSONDecodeError as exc:
            problem = f"the request is not JSON: {exc}"
    if not problem and not isinstance(value, dict):
        problem = 'the request must be a JSON object like {"action": "pause"}'
    if problem:
        response.bool_value, response.string_value = False, problem
        return None
    assert isinstance(value, dict)
    return value
