"""Skills that run on a remote skill server: a registry of ROS action (or service) clients."""

from __future__ import annotations

import json
import secrets
import time
from collections.abc import Callable
from typing import Any

import smach
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.planning.types import PlanStep
from plan_bridge.ros.protocol import (
    FACTS_SERVICE,
    INFO_SERVICE,
    PERFORM_DONE,
    PERFORM_HOLD,
    PERFORM_SERVICE,
    REPORT_SERVICE,
    SUBMIT_SERVICE,
    action_topic,
    decode_result,
    interfaces,
)
from plan_bridge.skills.registry import SkillRegistry
from smach.ros import ServiceState, SimpleActionState
from smach.ros.rclpy_api import GoalStatus

__all__ = ["remote_facts", "remote_info", "ros_skill", "ros_skills"]

TRANSPORTS = ("action", "service")


def ros_skill(
    node: Any,
    step: PlanStep,
    *,
    prefix: str = "skills",
    transport: str = "action",
    server_wait_timeout: float = 10.0,
    exec_timeout: float | None = None,
    preempt_timeout: float = 10.0,
    peer_alive: Callable[[], bool] | None = None,
) -> smach.State:
    """The state that performs ``step`` on the skill server under ``prefix``.

    Outcomes ``succeeded``, ``aborted``, ``preempted``; writes ``observations``.

    ``transport="action"`` (default): a StateMachine SUBMIT -> RUN -> REPORT of a
    :class:`~smach.ros.ServiceState`, a :class:`~smach.ros.SimpleActionState` on
    ``PREFIX/ACTION`` (a preempt cancels the remote goal) and a ServiceState reading
    the outcome and observations (see :mod:`plan_bridge.ros.protocol`).
    ``transport="service"``: a StateMachine BEGIN -> PERFORM, the ServiceState
    PERFORM asking ``PREFIX/perform`` about one request id until the action is done
    (a lost reply is sent again; ``exec_timeout`` and a preempt abandon the call
    and the robot finishes the action).
    ``peer_alive()``: the caller's own check that the robot lives (a heartbeat, its
    process), given to every state, so a call or goal in progress aborts when it
    answers false twice in a row, without waiting for the robot's DDS lease.
    """
    fibonacci, basic_types, _ = interfaces()
    text = str(step)
    outcomes = ["succeeded", "aborted", "preempted"]

    @smach.cb_interface(output_keys=["observations"], outcomes=outcomes)
    def read_result(ud: smach.UserData, response: Any) -> str:
        try:
            outcome, observations, detail = decode_result(response.string_value)
        except ValueError as exc:
            smach.logerr(f"skill {text}: malformed result from the skill server: {exc}")
            return "aborted"
        ud.observations = observations
        if detail:
            smach.loginfo(f"skill {text}: {detail}")
        return outcome

    if transport == "service":
        return _performed_skill(
            node, text, read_result, prefix, server_wait_timeout, exec_timeout, peer_alive
        )
    if transport != "action":
        raise ValueError(f"unknown transport {transport!r}; transports: {', '.join(TRANSPORTS)}")

    @smach.cb_interface(output_keys=["ticket"], outcomes=["refused"])
    def take_ticket(ud: smach.UserData, response: Any) -> str:
        if response.int64_value <= 0:
            smach.logerr(f"skill {text}: the skill server refused it: {response.string_value}")
            return "refused"
        ud.ticket = response.int64_value
        return "succeeded"

    @smach.cb_interface(input_keys=["ticket"])
    def ticket_goal(ud: smach.UserData, goal: Any) -> Any:
        return fibonacci.Goal(order=ud.ticket)

    @smach.cb_interface(input_keys=["ticket"])
    def ticket_request(ud: smach.UserData, request: Any) -> Any:
        request = basic_types.Request()
        request.int64_value = ud.ticket
        return request

    submit = basic_types.Request()
    submit.string_value = text
    # Submitting and reading a report are idempotent: a request lost while DDS still
    # matches a freshly started server is sent again after two seconds.
    quick = min(server_wait_timeout, 2.0)
    # The report comes from the process that just ran the goal.
    report_wait = min(server_wait_timeout, 2.0)

    def ran_and_failed(ud: smach.UserData, status: int, result: Any) -> str | None:
        # The server ran the action and it failed: its report says what the robot saw.
        # Without a result (server gone, goal rejected) there is nobody to ask.
        return "failed" if status == GoalStatus.STATUS_ABORTED else None

    def idempotent(service: str, wait: float, **callbacks: Any) -> ServiceState:
        """A call of ``PREFIX/service`` sent again when no answer came (see above)."""
        return ServiceState(
            node,
            f"{prefix}/{service}",
            basic_types,
            server_wait_timeout=wait,
            call_timeout=quick,
            call_attempts=3,
            peer_alive=peer_alive,
            **callbacks,
        )

    sm = smach.StateMachine(outcomes=outcomes, output_keys=["observations"])
    with sm:
        smach.StateMachine.add(
            "SUBMIT",
            idempotent(
                SUBMIT_SERVICE, server_wait_timeout, request=submit, response_cb=take_ticket
            ),
            transitions={"succeeded": "RUN", "refused": "aborted"},
        )
        smach.StateMachine.add(
            "RUN",
            SimpleActionState(
                node,
                action_topic(prefix, step.action),
                fibonacci,
                goal_cb=ticket_goal,
                server_wait_timeout=server_wait_timeout,
                exec_timeout=exec_timeout,
                preempt_timeout=preempt_timeout,
                result_cb=ran_and_failed,
                outcomes=["failed"],
                peer_alive=peer_alive,
            ),
            # A failed action still reports what the robot saw.
            transitions={"succeeded": "REPORT", "failed": "REPORT_FAILURE"},
        )
        for label, final in (("REPORT", None), ("REPORT_FAILURE", "aborted")):
            smach.StateMachine.add(
                label,
                idempotent(
                    REPORT_SERVICE, report_wait, request_cb=ticket_request, response_cb=read_result
                ),
                transitions={} if final is None else {"succeeded": final},
            )
    return sm


def _performed_skill(
    node: Any,
    text: str,
    read_result: Any,
    prefix: str,
    server_wait_timeout: float,
    exec_timeout: float | None,
    peer_alive: Callable[[], bool] | None,
) -> smach.StateMachine:
    """The service transport's skill: ``perform`` polled under one request id."""
    _, basic_types, _ = interfaces()
    outcomes = ["succeeded", "aborted", "preempted"]

    @smach.cb_interface(output_keys=["request_id", "deadline"], outcomes=["succeeded"])
    def begin(ud: smach.UserData) -> str:
        # A fresh id per execution: a retried skill performs the action again.
        ud.request_id = secrets.randbits(62) + 1
        ud.deadline = None if exec_timeout is None else time.monotonic() + exec_timeout
        return "succeeded"

    @smach.cb_interface(input_keys=["request_id"])
    def ask(ud: smach.UserData, request: Any) -> Any:
        request = basic_types.Request()
        request.string_value = text
        request.int64_value = ud.request_id
        request.float64_value = PERFORM_HOLD
        return request

    @smach.cb_interface(input_keys=["deadline"], output_keys=["observations"], outcomes=["running"])
    def answer(ud: smach.UserData, response: Any) -> str:
        if response.int64_value == PERFORM_DONE:
            return str(read_result(ud, response))
        if ud.deadline is not None and time.monotonic() >= ud.deadline:
            smach.logerr(
                f"skill {text}: not done after {exec_timeout} s (exec_timeout); "
                "the robot finishes it unwatched"
            )
            return "aborted"
        return "running"

    # A reply lost on the way is asked for again after the hold and a grace period.
    grace = min(server_wait_timeout, 2.0)
    sm = smach.StateMachine(outcomes=outcomes, output_keys=["observations"])
    with sm:
        smach.StateMachine.add("BEGIN", smach.CBState(begin), transitions={"succeeded": "PERFORM"})
        smach.StateMachine.add(
            "PERFORM",
            ServiceState(
                node,
                f"{prefix}/{PERFORM_SERVICE}",
                basic_types,
                request_cb=ask,
                response_cb=answer,
                server_wait_timeout=server_wait_timeout,
                call_timeout=PERFORM_HOLD + grace,
                call_attempts=3,
                peer_alive=peer_alive,
            ),
            transitions={"running": "PERFORM"},
        )
    return sm


def ros_skills(
    node: Any,
    task: PlanningTask,
    *,
    prefix: str = "skills",
    transport: str = "action",
    registry: SkillRegistry | None = None,
    **options: Any,
) -> SkillRegistry:
    """A registry whose actions (those without a registered skill) run remotely.

    Every action of ``task`` becomes a :func:`ros_skill` client of the skill server
    (``python -m plan_bridge.ros.skill_server``) under ``prefix``. ``options`` go
    to :func:`ros_skill` (timeouts).
    """
    if transport not in TRANSPORTS:
        raise ValueError(f"unknown transport {transport!r}; transports: {', '.join(TRANSPORTS)}")
    del task  # any action of the task is served; kept for symmetry with symbolic_skills
    registry = registry or SkillRegistry()
    registry.fallback = lambda step: ros_skill(
        node, step, prefix=prefix, transport=transport, **options
    )
    return registry


def _trigger(node: Any, service: str, timeout: float) -> str:
    """Call a ``std_srvs/Trigger`` service of the skill server: its message."""
    _, _, trigger = interfaces()
    state = ServiceState(
        node,
        service,
        trigger,
        response_key="response",
        server_wait_timeout=timeout,
        call_timeout=timeout / 3,
        call_attempts=3,
    )
    ud = smach.UserData()
    try:
        if state.execute(ud) != "succeeded":
            raise RuntimeError(f"the skill server's {service} did not answer within {timeout:g} s")
        return str(ud.response.message)
    finally:
        state.destroy()


def remote_facts(node: Any, *, prefix: str = "skills", timeout: float = 10.0) -> list[str]:
    """The facts true in the skill server's world (its ``facts`` service), as text."""
    facts = json.loads(_trigger(node, f"{prefix}/{FACTS_SERVICE}", timeout))
    return [f"({fact})" for fact in facts]


def remote_info(node: Any, *, prefix: str = "skills", timeout: float = 10.0) -> dict[str, Any]:
    """The skill server's ``info``: its task, seed, fault rate, faults, world clock...

    RuntimeError if it does not answer within ``timeout`` or answers nonsense.
    """
    text = _trigger(node, f"{prefix}/{INFO_SERVICE}", timeout)
    try:
        info = json.loads(text) if len(text) < 1_000_000 else None
    except ValueError:
        info = None
    if not isinstance(info, dict):
        raise RuntimeError(f"the skill server's {prefix}/{INFO_SERVICE} answered malformed JSON")
    return info
