"""``ActionServerWrapper``: serve a container as a ROS 2 action.

Each accepted goal runs the container once: the goal goes into the wrapper's
userdata under ``goal_key`` (and field by field with ``goal_slots_map`` /
``expand_goal_slots``); feedback is published whenever the container writes
``feedback_key`` (a Feedback message) or one of the keys of ``feedback_slots_map``,
and after each transition if a feedback message is present; the result is taken
from ``result_key``, ``result_slots_map`` and ``pack_result_slots``. The container's
outcome decides the terminal state: one of ``succeeded_outcomes`` -> succeed, of
``preempted_outcomes`` -> canceled (when the client asked for it), anything else ->
abort. A cancel request preempts the container (``request_preempt`` returns at
once; no polling thread). One goal runs at a time: a goal arriving while another
runs is rejected (a container cannot run twice at once).

The server is active as soon as the wrapper is built (as in the ROS 2 original);
``run_server()`` is kept for ROS 1 code and does nothing.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Mapping
from typing import Any

import smach
from smach.introspection.events import Event, Transition, UserdataWritten
from smach.ros._api import ActionServer, CancelResponse, GoalResponse, InvalidHandle, RCLError
from smach.ros.executor import SmachExecutor
from smach.ros.shared_node import node_optional

__all__ = ["ActionServerWrapper"]


class ActionServerWrapper:
    """Expose ``wrapped_container`` as the action ``server_name`` (resolved against ``node``)."""

    @node_optional
    def __init__(
        self,
        node: Any,
        server_name: str,
        action_spec: Any,
        wrapped_container: smach.Container,
        succeeded_outcomes: Iterable[str] | None = None,
        aborted_outcomes: Iterable[str] | None = None,
        preempted_outcomes: Iterable[str] | None = None,
        goal_key: str = "action_goal",
        feedback_key: str = "action_feedback",
        result_key: str = "action_result",
        goal_slots_map: Mapping[str, str] | None = None,
        feedback_slots_map: Mapping[str, str] | None = None,
        result_slots_map: Mapping[str, str] | None = None,
        expand_goal_slots: bool = False,
        pack_result_slots: bool = False,
    ) -> None:
        self._node = node
        self._spec = action_spec
        self.wrapped_container = wrapped_container
        self.succeeded_outcomes = list(succeeded_outcomes or ())
        self.aborted_outcomes = list(aborted_outcomes or ())
        self.preempted_outcomes = list(preempted_outcomes or ())
        overlap = (
            (set(self.succeeded_outcomes) & set(self.aborted_outcomes))
            | (set(self.succeeded_outcomes) & set(self.preempted_outcomes))
            | (set(self.aborted_outcomes) & set(self.preempted_outcomes))
        )
        if overlap:
            raise smach.InvalidStateError(
                f"ActionServerWrapper {server_name!r}: outcomes {sorted(overlap)} are listed "
                "in more than one of succeeded/aborted/preempted_outcomes"
            )
        self._goal_key = goal_key
        self._feedback_key = feedback_key
        self._result_key = result_key
        self._goal_slots_map = dict(goal_slots_map or {})
        self._feedback_slots_map = dict(feedback_slots_map or {})
        self._result_slots_map = dict(result_slots_map or {})
        self._expand_goal_slots = expand_goal_slots
        self._pack_result_slots = pack_result_slots

        goal_fields = list(action_spec.Goal.get_fields_and_field_types())
        keys = [goal_key, feedback_key, result_key, *self._goal_slots_map.values()]
        if expand_goal_slots:
            keys += goal_fields
        wrapped_container.register_input_keys(keys)
        wrapped_container.register_output_keys(
            [feedback_key, result_key, *self._result_slots_map.values()]
        )

        #: The userdata the container runs in (its parent scope).
        self.userdata = smach.UserData()
        self._busy = threading.Lock()
        self._goal_handle: Any = None
        self._closing = False
        self._feedback_keys = {feedback_key, *self._feedback_slots_map.values()}

        helper = SmachExecutor.for_node(node)
        self._resolved_name: str = node.resolve_topic_name(server_name)
        self._server: Any = ActionServer(
            helper.node,
            action_spec,
            self._resolved_name,
            execute_callback=self._execute,
            goal_callback=self._on_goal,
            cancel_callback=self._on_cancel,
            callback_group=helper.callback_group,
        )
        wrapped_container.add_listener(self._on_event)

    def run_server(self) -> ActionServerWrapper:
        """Kept for ROS 1 code: the server already runs."""
        return self

    @property
    def action_name(self) -> str:
        return self._resolved_name

    # -- action server callbacks (executor threads) ---------------------------------------------
    def _on_goal(self, goal: Any) -> Any:
        if self._closing:
            return GoalResponse.REJECT
        if self._busy.locked():
            smach.logwarn(
                f"ActionServerWrapper {self._resolved_name}: rejecting a goal, "
                "the container is running another one"
            )
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_cancel(self, goal_handle: Any) -> Any:
        if goal_handle is self._goal_handle:
            self.wrapped_container.request_preempt()
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle: Any) -> Any:
        if not self._busy.acquire(blocking=False):
            goal_handle.abort()
            return self._spec.Result()
        try:
            self._goal_handle = goal_handle
            if goal_handle.is_cancel_requested:
                goal_handle.canceled()
                return self._spec.Result()
            return self._run(goal_handle)
        except (InvalidHandle, RCLError) as exc:
            if not self._closing:
                raise
            # destroy() gave the goal its time; the server went away under it.
            smach.logwarn(
                f"ActionServerWrapper {self._resolved_name}: the server was destroyed while "
                f"a goal ran ({type(exc).__name__}: {exc})"
            )
            return self._spec.Result()
        finally:
            self._goal_handle = None
            self._busy.release()

    def _run(self, goal_handle: Any) -> Any:
        goal = goal_handle.request
        ud = self.userdata
        ud[self._goal_key] = goal
        ud[self._result_key] = self._spec.Result()
        ud[self._feedback_key] = self._spec.Feedback()
        if self._expand_goal_slots:
            for name in self._spec.Goal.get_fields_and_field_types():
                ud[name] = getattr(goal, name)
        for field, key in self._goal_slots_map.items():
            ud[key] = getattr(goal, field)

        try:
            outcome = self.wrapped_container.execute(ud)
        except Exception as exc:
            smach.logerr(
                f"ActionServerWrapper {self._resolved_name}: the container raised "
                f"{type(exc).__name__}: {exc}; aborting the goal"
            )
            goal_handle.abort()
            return self._spec.Result()

        result = self._result(ud)
        if outcome in self.succeeded_outcomes:
            goal_handle.succeed()
        elif outcome in self.preempted_outcomes and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:
            if outcome not in self.aborted_outcomes and outcome not in self.preempted_outcomes:
                smach.logwarn(
                    f"ActionServerWrapper {self._resolved_name}: outcome {outcome!r} is in none "
                    "of succeeded/aborted/preempted_outcomes; aborting the goal"
                )
            goal_handle.abort()
        return result

    def _result(self, ud: smach.UserData) -> Any:
        result = _lookup(ud, self._result_key)
        if not isinstance(result, self._spec.Result):
            result = self._spec.Result()
        for field, key in self._result_slots_map.items():
            if key in ud:
                setattr(result, field, ud[key])
        if self._pack_result_slots:
            for field in self._spec.Result.get_fields_and_field_types():
                if field in ud:
                    setattr(result, field, ud[field])
        return result

    # -- feedback (the container's thread) ----------------------------------------------------------
    def _on_event(self, event: Event) -> None:
        goal_handle = self._goal_handle
        if goal_handle is None:
            return
        if isinstance(event, UserdataWritten):
            if event.key not in self._feedback_keys or event.path != self.wrapped_container.path:
                return
        elif not isinstance(event, Transition):
            return
        feedback = self._feedback()
        if feedback is None:
            return
        try:
            goal_handle.publish_feedback(feedback)
        except (InvalidHandle, RCLError):
            # While destroy() runs, the server may go first: the feedback has nobody to go to.
            if not self._closing:
                raise

    def _feedback(self) -> Any:
        data = self.wrapped_container.userdata
        feedback = _lookup(data, self._feedback_key)
        if not isinstance(feedback, self._spec.Feedback):
            if not self._feedback_slots_map:
                return None
            feedback = self._spec.Feedback()
        for field, key in self._feedback_slots_map.items():
            if key in data:
                setattr(feedback, field, data[key])
        return feedback

    def destroy(self, timeout: float = 5.0) -> None:
        """Stop serving (the action disappears from the ROS graph).

        A goal still running has its container preempted and ``timeout`` seconds to
        end before the server goes, so that it does not fail in its executor thread
        on a destroyed server; new goals are rejected meanwhile.
        """
        self._closing = True
        if self._busy.locked():
            self.wrapped_container.request_preempt()
            if self._busy.acquire(timeout=timeout):
                self._busy.release()
        self.wrapped_container.remove_listener(self._on_event)
        self._server.destroy()


def _lookup(ud: smach.UserData, key: str) -> Any:
    """``ud[key]``, or None when the key is missing (UserData has no ``get``)."""
    try:
        return ud[key]
    except KeyError:
        return None
