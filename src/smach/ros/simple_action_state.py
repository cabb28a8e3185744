"""``SimpleActionState``: send one goal to a ROS 2 action server and wait for its result.

Every wait is bounded and preemptable:

* waiting for the server: ``server_wait_timeout`` -> ``aborted``; a preempt -> ``preempted``;
* waiting for the server to accept the goal: ``server_wait_timeout`` -> ``aborted``;
  a rejected goal -> ``aborted`` (the original hung);
* the active goal: ``exec_timeout`` -> the goal is cancelled, then ``aborted``; a preempt
  -> the goal is cancelled, then ``preempted`` once the server reports it cancelled;
  a server that leaves the ROS graph (``server_is_ready()`` turns false, checked every
  ``liveness_period`` seconds) -> ``aborted``. A crashed server process leaves the graph
  when its DDS participant lease expires (Fast DDS: 20 s by default, see docs/ros.md),
  or ``peer_alive()`` (the caller's own check, if given) answers false twice in a row;
* cancelling: the server has ``preempt_timeout`` seconds to finish; otherwise ``aborted``.

``request_preempt()`` returns at once (the original blocked the caller, and with it the
whole container, for up to ``preempt_timeout``). Outcomes follow the goal's terminal
status: SUCCEEDED -> ``succeeded``; CANCELED after our own preempt -> ``preempted``;
ABORTED, CANCELED by somebody else, exec timeout, anything else -> ``aborted`` (the ROS 2
original reported a server abort as ``preempted``). ``result_cb`` overrides.
"""

from __future__ import annotations

import collections
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import smach
from smach.ros._api import ActionClient, GoalStatus
from smach.ros.executor import seconds
from smach.ros.ros_state import RosState
from smach.ros.shared_node import node_optional

__all__ = ["SimpleActionState"]

DEFAULT_OUTCOMES = ("succeeded", "aborted", "preempted")
#: Feedback messages kept while the executing thread is busy (older ones are dropped).
FEEDBACK_QUEUE = 100


class _Run:
    """What the callbacks of one goal report; one per execution, so that late
    callbacks of an earlier goal cannot touch a later one."""

    def __init__(self) -> None:
        self.goal_handle: Any = None
        self.goal_response = False
        self.result: Any = None  # the GetResult response (status + result)
        self.error: BaseException | None = None
        self.feedback: collections.deque[Any] = collections.deque(maxlen=FEEDBACK_QUEUE)


class SimpleActionState(RosState):
    """A state that sends a goal to an action server and waits for the result.

    Signature of the ROS 2 smach_ros (the node first), plus ``feedback_cb``,
    ``liveness_period`` and ``peer_alive`` (the caller's own check that the server
    lives, e.g. a heartbeat: two false answers in a row, ``liveness_period`` apart,
    abort an active goal without waiting for the DDS lease). Timeouts accept float seconds or an rclpy ``Duration``.
    ``outcomes`` are added to ``succeeded``, ``aborted`` and ``preempted``.

    Callbacks run in the thread executing the state:
    ``goal_cb(ud, goal, *args, **kwargs)`` may return a new goal;
    ``feedback_cb(ud, feedback, *args, **kwargs)`` for each feedback message;
    ``result_cb(ud, status, result, *args, **kwargs)`` gets the ``GoalStatus`` code and
    may return an outcome. A callback decorated with :func:`smach.cb_interface`
    contributes its keys and outcomes.
    """

    @node_optional
    def __init__(
        self,
        node: Any,
        action_name: str,
        action_spec: Any,
        goal: Any = None,
        goal_key: str | None = None,
        goal_slots: Sequence[str] | None = None,
        goal_cb: Callable[..., Any] | None = None,
        goal_cb_args: Sequence[Any] | None = None,
        goal_cb_kwargs: Mapping[str, Any] | None = None,
        result_key: str | None = None,
        result_slots: Sequence[str] | None = None,
        result_cb: Callable[..., Any] | None = None,
        result_cb_args: Sequence[Any] | None = None,
        result_cb_kwargs: Mapping[str, Any] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        outcomes: Iterable[str] | None = None,
        exec_timeout: Any = None,
        preempt_timeout: Any = 60.0,
        server_wait_timeout: Any = 60.0,
        *,
        feedback_cb: Callable[..., Any] | None = None,
        feedback_cb_args: Sequence[Any] | None = None,
        feedback_cb_kwargs: Mapping[str, Any] | None = None,
        liveness_period: Any = 0.5,
        peer_alive: Callable[[], bool] | None = None,
    ) -> None:
        super().__init__(node, outcomes=[*DEFAULT_OUTCOMES, *(outcomes or ())])
        self._ros_name = self._action_name = action_name
        self._spec = action_spec
        self._exec_timeout = seconds(exec_timeout, "exec_timeout")
        self._preempt_timeout: float = (
            seconds(preempt_timeout, "preempt_timeout", allow_none=False) or 0.0
        )
        self._server_wait_timeout = seconds(server_wait_timeout, "server_wait_timeout")
        self._liveness_period = seconds(liveness_period, "liveness_period")
        self._set_peer_alive(peer_alive)

        if goal is None:
            goal = action_spec.Goal()
        elif callable(goal):
            raise smach.InvalidStateError(
                f"SimpleActionState {action_name!r}: goal must be a goal message, not a "
                "callable (use goal_cb)"
            )
        self._goal = goal
        self._goal_key = goal_key
        self._goal_slots = list(goal_slots or ())
        self._check_slots("goal_slots", self._goal_slots, action_spec.Goal)
        self._result_key = result_key
        self._result_slots = list(result_slots or ())
        self._check_slots("result_slots", self._result_slots, action_spec.Result)

        self._goal_cb = self._callback("goal_cb", goal_cb, goal_cb_args, goal_cb_kwargs)
        self._result_cb = self._callback("result_cb", result_cb, result_cb_args, result_cb_kwargs)
        self._feedback_cb = self._callback(
            "feedback_cb", feedback_cb, feedback_cb_args, feedback_cb_kwargs
        )

        self._declare_keys(
            input_keys, output_keys, (goal_key, self._goal_slots), (result_key, self._result_slots)
        )

        helper = self._helper()
        self._resolved_name: str = node.resolve_topic_name(action_name)
        self._client: Any = ActionClient(
            helper.node, action_spec, self._resolved_name, callback_group=helper.callback_group
        )
        self._helper_node: Any = helper.node

    # -- running ------------------------------------------------------------------------
    def _server_ready(self) -> bool:
        return bool(self._client.server_is_ready())

    def execute(self, ud: smach.UserData) -> str:
        return self._guarded(lambda: self._execute(ud))

    def _execute(self, ud: smach.UserData) -> str:
        absent = self._wait_for_peer(
            self._server_ready, f"action server {self._resolved_name!r}", self._server_wait_timeout
        )
        if absent is not None:
            return absent
        goal = self._compose(
            ud, "goal", self._goal, self._goal_key, self._goal_slots, self._goal_cb, self._spec.Goal
        )
        run = _Run()
        self._wake.clear()
        send = self._client.send_goal_async(
            goal, feedback_callback=lambda msg: self._on_feedback(run, msg)
        )
        send.add_done_callback(lambda future: self._on_goal_response(run, future))
        return self._follow(ud, run)

    # Callbacks from the executor thread: store and wake, nothing else.
    def _on_goal_response(self, run: _Run, future: Any) -> None:
        try:
            run.goal_handle = future.result()
        except Exception as exc:
            run.error = exc
        run.goal_response = True
        if run.goal_handle is not None and run.goal_handle.accepted:
            result_future = run.goal_handle.get_result_async()
            result_future.add_done_callback(lambda f: self._on_result(run, f))
        self._wake.set()

    def _on_result(self, run: _Run, future: Any) -> None:
        try:
            run.result = future.result()
        except Exception as exc:
            run.error = exc
        self._wake.set()

    def _on_feedback(self, run: _Run, message: Any) -> None:
        run.feedback.append(message.feedback)
        self._wake.set()

    def _follow(self, ud: smach.UserData, run: _Run) -> str:
        """Wait for the goal to end, cancelling it on preempt or exec timeout."""
        start = time.monotonic()
        response_deadline = (
            None if self._server_wait_timeout is None else start + self._server_wait_timeout
        )
        exec_deadline = None if self._exec_timeout is None else start + self._exec_timeout
        cancel_deadline: float | None = None
        cancel_reason = ""
        liveness = self._liveness(self._server_ready, self._liveness_period, start)

        while True:
            self._drain_feedback(ud, run)
            now = time.monotonic()
            if run.error is not None:
                return self._fail(
                    f"action {self._resolved_name!r} failed: {type(run.error).__name__}: "
                    f"{run.error}"
                )
            if run.goal_response and (run.goal_handle is None or not run.goal_handle.accepted):
                return self._fail(f"action server {self._resolved_name!r} rejected the goal")
            if run.result is not None:
                return self._finish(ud, run, cancel_reason)

            if not run.goal_response:
                if response_deadline is not None and now >= response_deadline:
                    return self._fail(
                        f"action server {self._resolved_name!r} did not answer the goal "
                        f"request within {self._server_wait_timeout} s"
                    )
            elif cancel_deadline is None:
                reason = ""
                if self.preempt_requested():
                    reason = "preempt"
                elif exec_deadline is not None and now >= exec_deadline:
                    reason = "exec_timeout"
                if reason:
                    cancel_reason = reason
                    cancel_deadline = now + self._preempt_timeout
                    run.goal_handle.cancel_goal_async()
            elif now >= cancel_deadline:
                what = "preempt" if cancel_reason == "preempt" else "exec_timeout cancel"
                return self._fail(
                    f"action server {self._resolved_name!r} did not finish cancelling the goal "
                    f"within {self._preempt_timeout} s (preempt_timeout) after a {what}"
                )

            if liveness.lost(now):
                return self._fail(
                    f"action server {self._resolved_name!r} disappeared while the goal was active"
                )

            timeouts = [
                t
                for t in (
                    liveness.next_check,
                    None if run.goal_response else response_deadline,
                    exec_deadline if cancel_deadline is None else cancel_deadline,
                )
                if t is not None
            ]
            wait = None if not timeouts else max(0.0, min(timeouts) - time.monotonic())
            # request_preempt() sets the wake event once and _wait clears it, so a
            # pending preempt does not make this loop spin.
            self._wait(wait)

    def _drain_feedback(self, ud: smach.UserData, run: _Run) -> None:
        while run.feedback:
            feedback = run.feedback.popleft()
            if self._feedback_cb is None:
                continue
            cb, args, kwargs = self._feedback_cb
            try:
                cb(ud, feedback, *args, **kwargs)
            except Exception as exc:
                smach.logerr(
                    f"{self.path or 'SimpleActionState'}: feedback_cb raised "
                    f"{type(exc).__name__}: {exc} (ignored)"
                )

    def _finish(self, ud: smach.UserData, run: _Run, cancel_reason: str) -> str:
        status = int(run.result.status)
        result = run.result.result
        if status == GoalStatus.STATUS_SUCCEEDED:
            outcome = "succeeded"
        elif status == GoalStatus.STATUS_CANCELED and self.preempt_requested():
            outcome = "preempted"
        else:
            outcome = "aborted"
            if status == GoalStatus.STATUS_ABORTED:
                smach.logwarn(f"{self.path or 'SimpleActionState'}: the server aborted the goal")
            elif cancel_reason == "exec_timeout":
                smach.logwarn(
                    f"{self.path or 'SimpleActionState'}: goal cancelled after exec_timeout "
                    f"{self._exec_timeout} s"
                )

        chosen = self._chosen_outcome("result_cb", self._result_cb, ud, status, result)
        outcome = chosen or outcome
        if result is not None:
            self._store(ud, result, self._result_key, self._result_slots)

        if outcome == "preempted":
            self.service_preempt()
        return str(outcome)

    # -- clean-up ----------------------------------------------------------------------------
    def destroy(self) -> None:
        """Release the action client (the state cannot execute afterwards)."""
        self._client.destroy()
