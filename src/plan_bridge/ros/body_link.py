"""Robots' bodies across processes: the world's process serves them, each robot's asks.

When every robot of a pyrobosim world runs as a process of its own (``plan-bridge run
--ros``), the world (pyrobosim, its clock, its events, its faults) lives in one
process, the *world node*, as a simulator does, and each *robot node* runs its robot's
skill machines (:mod:`plan_bridge.robosim.skills`). A skill's ``PLAN``, ``DRIVE``,
``ACT`` and ``LOOK`` are then calls of the world node's body service:

``PREFIX/body`` (``test_msgs/srv/BasicTypes``): ``request.string_value`` is the call as
JSON, ``{"op": "plan" | "drive" | "act" | "look", "robot": NAME, "action": ACTION,
"args": [...], "route": N}`` (``route``: the handle a ``plan`` gave, for its
``drive``), ``request.int64_value`` a request id the robot draws per call and
``request.float64_value`` how long the world may hold the reply (at most
:data:`~plan_bridge.ros.protocol.MAX_PERFORM_HOLD`), as ``perform`` does: the first
request with an id starts the call, the reply is
:data:`~plan_bridge.ros.protocol.PERFORM_DONE` with the JSON result ``{"status",
"message", "route", "observations"}`` or :data:`~plan_bridge.ros.protocol.PERFORM_RUNNING`,
and the robot asks again under the same id (a lost reply costs a resend, never a
second drive).

``PREFIX/body_cancel`` (``BasicTypes``, ``int64_value`` the request id): stop the call
(the drive stops where the robot is; the result comes as ``CANCELED``).

A call whose robot stops asking for :data:`ORPHAN_S` seconds is cancelled: the robot's
process is gone, so its body stops where it is, as a robot base does when its
controller dies.
"""

from __future__ import annotations

import json
import secrets
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from plan_bridge.belief import Observation
from plan_bridge.robosim.body import Body, Preempted, WorldBody
from plan_bridge.robosim.results import ActionResult
from plan_bridge.robosim.skills import ACTIONS
from plan_bridge.robosim.world import RobosimWorld
from plan_bridge.ros.protocol import (
    MAX_PAYLOAD,
    MAX_PERFORM_HOLD,
    PERFORM_DONE,
    PERFORM_HOLD,
    PERFORM_RUNNING,
    decode_observations,
    encode_observations,
    interfaces,
)

__all__ = ["BODY_CANCEL_SERVICE", "BODY_SERVICE", "ORPHAN_S", "BodyServer", "RemoteBody"]

BODY_SERVICE = "body"
BODY_CANCEL_SERVICE = "body_cancel"
#: Seconds without a request from its robot after which a running call is cancelled.
ORPHAN_S = 3.0
#: Body calls kept after they ended (a late repeat of an older id starts nothing).
MAX_KEPT = 1000
OPS = ("plan", "drive", "act", "look")


class _Call:
    """One body call on the world's side: its request, then its result."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.asked = time.monotonic()
        self.cancelled = False
        self.done = threading.Event()
        self.result = ""

    def preempted(self) -> bool:
        return self.cancelled or time.monotonic() - self.asked > ORPHAN_S

    def finish(
        self, result: ActionResult, route: int | None = None, seen: Iterable[Observation] = ()
    ) -> None:
        self.result = json.dumps(
            {
                "status": result.status,
                "message": result.message,
                "route": route,
                "observations": encode_observations(seen),
            }
        )
        self.done.set()


class BodyServer:
    """Serves the bodies of ``world``'s robots on ``node`` under ``prefix`` (see the
    module's doc); ``log`` gets a line per call that failed to start. The caller spins
    ``node`` with a multi-threaded executor (a held reply blocks its thread)."""

    def __init__(
        self,
        node: Any,
        world: RobosimWorld,
        *,
        prefix: str,
        log: Callable[[str], None] | None = None,
    ) -> None:
        from smach.ros.rclpy_api import ReentrantCallbackGroup

        _, basic_types, _ = interfaces()
        self.node = node
        self.world = world
        self.body = WorldBody(world)
        self.prefix = prefix.rstrip("/")
        self._log = log or (lambda line: None)
        self._lock = threading.Lock()
        self._calls: dict[int, _Call] = {}
        self._routes: dict[int, Any] = {}
        self._next_route = 1
        group = ReentrantCallbackGroup()
        self._services = [
            node.create_service(
                basic_types, f"{self.prefix}/{name}", callback, callback_group=group
            )
            for name, callback in (
                (BODY_SERVICE, self._on_call),
                (BODY_CANCEL_SERVICE, self._on_cancel),
            )
        ]

    # -- services -------------------------------------------------------------------------
    def _on_call(self, request: Any, response: Any) -> Any:
        ident = int(request.int64_value)
        call = self._call(ident, str(request.string_value))
        call.asked = time.monotonic()
        hold = float(request.float64_value)
        call.done.wait(min(hold, MAX_PERFORM_HOLD) if hold > 0 else MAX_PERFORM_HOLD)
        call.asked = time.monotonic()
        response.int64_value = PERFORM_DONE if call.done.is_set() else PERFORM_RUNNING
        response.string_value = call.result
        return response

    def _on_cancel(self, request: Any, response: Any) -> Any:
        with self._lock:
            call = self._calls.get(int(request.int64_value))
        if call is not None:
            call.cancelled = True
        response.bool_value = call is not None
        return response

    def _call(self, ident: int, text: str) -> _Call:
        """The call of request ``ident``: started now unless it is a repeat."""
        with self._lock:
            call = self._calls.get(ident)
            if call is not None and call.text == text:
                return call
            fresh = _Call(text)
            if call is not None:
                fresh.finish(ActionResult("INVALID_ACTION", f"request id {ident} was reused"))
                return fresh
            self._calls[ident] = fresh
            ended = [k for k, c in self._calls.items() if c.done.is_set()]
            for forgotten in ended[: max(0, len(self._calls) - MAX_KEPT)]:
                del self._calls[forgotten]
        threading.Thread(target=self._run, args=(fresh,), name=f"body-{ident}", daemon=True).start()
        return fresh

    # -- calls ------------------------------------------------------------------------------
    def _run(self, call: _Call) -> None:
        try:
            op, robot, action, args, route = self._read(call.text)
        except ValueError as exc:
            self._log(f"body: refused {call.text[:200]}: {exc}")
            call.finish(ActionResult("INVALID_ACTION", str(exc)))
            return
        changes = len(self.world.changes)
        try:
            # Robots act at once here: each call spends time on its own timeline.
            with self.world.own_timeline():
                self._perform(call, op, robot, action, args, route)
        except Exception as exc:  # the robot hears of it as the call's failure
            call.finish(ActionResult("EXECUTION_FAILURE", f"{type(exc).__name__}: {exc}"))
        for change in self.world.changes[changes:]:
            self._log(f"world {change}")

    def _perform(
        self, call: _Call, op: str, robot: str, action: str, args: list[str], route: Any
    ) -> None:
        body = self.body
        if op == "look":
            call.finish(ActionResult("SUCCESS"), seen=body.look(robot, args))
        elif op == "act":
            call.finish(body.act(robot, action, args, call.preempted))
        elif op == "plan":
            planned, result = body.plan(robot, action, args)
            handle = None
            if planned is not None:
                with self._lock:
                    handle = self._next_route
                    self._next_route += 1
                    self._routes[handle] = planned
                    while len(self._routes) > MAX_KEPT:
                        del self._routes[next(iter(self._routes))]
            call.finish(result, handle)
        else:
            call.finish(body.drive(robot, action, args, route, call.preempted))

    def _read(self, text: str) -> tuple[str, str, str, list[str], Any]:
        """(op, robot, action, args, route object) of a call; ValueError saying why not."""
        if len(text) > MAX_PAYLOAD:
            raise ValueError("the call is too long")
        data = json.loads(text)
        if not isinstance(data, dict):
            raise ValueError("a body call is a JSON object")
        op, robot, action = data.get("op"), data.get("robot"), data.get("action")
        args = data.get("args")
        if op not in OPS:
            raise ValueError(f"op {op!r} is not one of {', '.join(OPS)}")
        if not isinstance(robot, str) or robot.lower() not in self.world.robots:
            raise ValueError(f"no robot {robot!r}; robots: {', '.join(self.world.robots)}")
        if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
            raise ValueError("args must be a list of names")
        if op != "look" and (action not in ACTIONS or len(args) != len(ACTIONS[action])):
            raise ValueError(f"{action!r} with {len(args)} arguments is not a robosim action")
        route = None
        if op == "drive":
            handle = data.get("route")
            with self._lock:
                route = self._routes.pop(handle, None) if isinstance(handle, int) else None
            if route is None:
                raise ValueError(f"no planned route {data.get('route')!r} to drive")
        return op, robot, str(action), args, route

    def destroy(self) -> None:
        with self._lock:
            calls = list(self._calls.values())
        for call in calls:
            call.cancelled = True
        for service in self._services:
            self.node.destroy_service(service)


class RemoteBody(Body):
    """A robot's body in the world node under ``prefix``, asked over ROS 2 from ``node``'s
    process (a :class:`~plan_bridge.robosim.body.Body` for the robosim skills).

    A call the world does not answer within ``server_wait_timeout`` seconds (the world
    node is gone) ends ``EXECUTION_FAILURE`` with the reason, never a hang.
    """

    def __init__(self, node: Any, prefix: str, *, server_wait_timeout: float = 10.0) -> None:
        from smach.ros.executor import SmachExecutor

        _, self._types, _ = interfaces()
        helper = SmachExecutor.for_node(node)
        self.prefix = prefix.rstrip("/")
        self.server_wait_timeout = server_wait_timeout
        self._client = helper.node.create_client(
            self._types, f"{self.prefix}/{BODY_SERVICE}", callback_group=helper.callback_group
        )
        self._cancel = helper.node.create_client(
            self._types,
            f"{self.prefix}/{BODY_CANCEL_SERVICE}",
            callback_group=helper.callback_group,
        )

    def plan(self, robot: str, action: str, args: Sequence[str]) -> tuple[Any, ActionResult]:
        reply = self._ask({"op": "plan", "robot": robot, "action": action, "args": list(args)})
        return reply.get("route"), _result(reply)

    def drive(
        self, robot: str, action: str, args: Sequence[str], route: Any, preempted: Preempted
    ) -> ActionResult:
        call = {"op": "drive", "robot": robot, "action": action, "args": list(args)}
        return _result(self._ask({**call, "route": route}, preempted))

    def act(
        self, robot: str, action: str, args: Sequence[str], preempted: Preempted
    ) -> ActionResult:
        call = {"op": "act", "robot": robot, "action": action, "args": list(args)}
        return _result(self._ask(call, preempted))

    def look(self, robot: str, about: Iterable[str]) -> list[Observation]:
        reply = self._ask({"op": "look", "robot": robot, "action": "", "args": list(about)})
        try:
            return decode_observations(reply.get("observations") or [])
        except ValueError:
            return []  # a malformed reading is no reading

    def _ask(self, call: dict[str, Any], preempted: Preempted | None = None) -> dict[str, Any]:
        """The world's JSON reply to ``call``, asked under one request id until done."""
        ident = secrets.randbits(62) + 1
        text = json.dumps(call)
        cancelled = False
        silent_since = time.monotonic()
        while True:
            if not cancelled and preempted is not None and preempted():
                cancelled = True
                self._send_cancel(ident)
            if not self._client.service_is_ready():
                if time.monotonic() - silent_since > self.server_wait_timeout:
                    return _failure(f"the world node under /{self.prefix} is not there")
                time.sleep(0.05)
                continue
            request = self._types.Request()
            request.string_value = text
            request.int64_value = ident
            # While a preempt is pending, ask briefly: the cancelled call ends soon.
            request.float64_value = 0.2 if cancelled else PERFORM_HOLD
            reply = self._wait(self._client.call_async(request), PERFORM_HOLD + 2.0)
            if reply is None:
                if time.monotonic() - silent_since > self.server_wait_timeout:
                    return _failure(
                        f"the world node under /{self.prefix} did not answer for "
                        f"{self.server_wait_timeout:g} s"
                    )
                continue
            silent_since = time.monotonic()
            if reply.int64_value == PERFORM_DONE:
                try:
                    data = json.loads(reply.string_value)
                except ValueError:
                    data = None
                return data if isinstance(data, dict) else _failure("a malformed reply")

    def _wait(self, future: Any, timeout: float) -> Any:
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout):
            self._client.remove_pending_request(future)
            return None
        try:
            return future.result()
        except Exception:
            return None

    def _send_cancel(self, ident: int) -> None:
        request = self._types.Request()
        request.int64_value = ident
        if self._cancel.service_is_ready():
            self._cancel.call_async(request)  # the call's reply says when it stopped


def _result(reply: dict[str, Any]) -> ActionResult:
    status = str(reply.get("status") or "EXECUTION_FAILURE")
    return ActionResult(status, str(reply.get("message") or ""))


def _failure(reason: str) -> dict[str, Any]:
    return {"status": "EXECUTION_FAILURE", "message": reason}
