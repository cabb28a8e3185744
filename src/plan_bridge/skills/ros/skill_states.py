"""The skills of ROS 2 skill-map entries: one plan step, one goal, call or wait.

:class:`RosSkill` is the factory a ROS entry registers: called with a step's
arguments, it returns a small ``smach.StateMachine`` (outcomes: the three, and the
entry's own) whose one state, :class:`RosCall`, labelled after the ROS name
(``/courier/drive`` -> ``DRIVE``), does the work with smach.ros's states:

* an action: a :class:`~smach.ros.SimpleActionState` sends the goal filled from the
  entry; a preempt cancels it on the server; the terminal status gives an outcome
  (``status``), then the first of the entry's ``outcomes`` conditions that holds on
  the result wins; the feedback is recorded as ``feedback`` says;
* a service: a :class:`~smach.ros.ServiceState` calls it; a condition on the
  response gives the outcome (default ``succeeded``);
* a topic: a :class:`~smach.ros.MonitorState` waits for the first message on which
  a condition holds (no conditions: any message) for ``timeout`` seconds.

The state writes what it sent and received to its machine's userdata (``goal``,
``feedback``, ``result``; ``request``, ``response``; ``message``) as plain data, so
the journal and the viewer show them. Nothing of ROS is touched until the step
runs: the states are built on the process's default node (``smach.ros.default_node``)
on first use and kept for later steps with the same name (no new client per step).

A server that disappeared during a goal or a call (the liveness check of
smach.ros: two failed checks, 0.5 s apart; a crashed process leaves the graph when
its DDS lease ends), or that did not come within ``server_wait``, is remembered as
gone: later steps that need it do not wait ``server_wait`` for it: a step aborts at once unless the server is back in the graph,
so the executive's retries and replans end quickly (as the steps of a lost robot
node do in :mod:`plan_bridge.ros.connection`).
"""

from __future__ import annotations

import inspect
import re
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import smach
from plan_bridge.skills.ros.types import assign, message_data

if TYPE_CHECKING:
    from plan_bridge.skills.ros.entries import RosEntry

__all__ = ["GONE_WAIT", "RosCall", "RosSkill", "forget_servers"]

#: Seconds a step waits for a server remembered as gone before it aborts (0: it
#: looks once: the executive's retries and replans look again).
GONE_WAIT = 0.0
#: Least seconds between two feedback records (the last one is always recorded).
FEEDBACK_PERIOD = 0.2
#: Seconds the server has to confirm a cancel after a preempt.
PREEMPT_TIMEOUT = 10.0
#: The keys a ROS skill writes, by kind of entry.
RECORD_KEYS = {
    "action": ("goal", "feedback", "result"),
    "service": ("request", "response"),
    "topic": ("message",),
}
_STATUS_NAMES = {4: "succeeded", 5: "canceled", 6: "aborted"}


class RosSkill:
    """The skill factory of a ROS entry: ``RosSkill(entry)(*arguments)`` is the step's
    state machine. Its signature takes the action's parameters, so
    :meth:`~plan_bridge.skills.registry.SkillRegistry.check` checks it like any factory."""

    def __init__(self, entry: RosEntry) -> None:
        self.entry = entry
        self.__signature__ = inspect.Signature(
            [
                inspect.Parameter(
                    name.replace("-", "_") or f"arg{i}", inspect.Parameter.POSITIONAL_ONLY
                )
                for i, name in enumerate(entry.parameters)
            ]
        )
        self.__qualname__ = self.__name__ = f"{entry.key} {entry.name}"
        self.__module__ = "skills.toml"

    def __call__(self, *arguments: str) -> smach.State:
        if len(arguments) != len(self.entry.parameters):
            raise TypeError(
                f"{self.__qualname__}: the action has {len(self.entry.parameters)} parameter(s), "
                f"got {len(arguments)} argument(s)"
            )
        entry = self.entry
        sm = smach.StateMachine(outcomes=list(entry.outcomes))
        with sm:
            smach.StateMachine.add(state_label(entry), RosCall(entry, arguments), transitions={})
        return sm

    def __eq__(self, other: object) -> bool:
        return isinstance(other, RosSkill) and other.entry == self.entry

    def __hash__(self) -> int:
        return hash((self.entry.key, self.entry.name, self.entry.type_name))

    def __repr__(self) -> str:
        return f"<{self.__qualname__} ({self.entry.type_name})>"


def state_label(entry: RosEntry) -> str:
    """The label of the entry's state: the last part of its ROS name, upper case."""
    last = re.sub(r"\{\?[\w-]+\}", "", entry.name).rstrip("/").rsplit("/", 1)[-1]
    label = re.sub(r"\W", "_", last).strip("_").upper()
    return label or f"ROS_{entry.kind.upper()}"


class RosCall(smach.State):
    """Sends one goal or request of a ROS entry (or waits for its message) and maps
    the answer to an outcome; see the module's description."""

    def __init__(self, entry: RosEntry, arguments: Sequence[str]) -> None:
        super().__init__(outcomes=list(entry.outcomes), output_keys=list(RECORD_KEYS[entry.kind]))
        self.entry = entry
        self.arguments = tuple(arguments)
        self.names = entry.names(arguments)
        self.ros_name = entry.ground_name(arguments)
        self._lock = threading.Lock()
        self._inner: Any = None

    def request_preempt(self) -> None:
        super().request_preempt()
        with self._lock:
            inner = self._inner
        if inner is not None:
            inner.request_preempt()

    def execute(self, ud: smach.UserData) -> str:
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        try:
            sent = self.compose()
            inner = _pool.take(self.entry, self.ros_name)
        except Exception as exc:
            return self._fail(f"cannot start: {type(exc).__name__}: {exc}")
        try:
            return self._run(ud, inner, sent)
        finally:
            with self._lock:
                self._inner = None
            inner.recall_preempt()
            _pool.give(self.entry, self.ros_name, inner)

    def compose(self) -> Any:
        """The goal or request of this step (None for a topic)."""
        kind = self.entry.sent_type
        if kind is None:
            return None
        message = kind()
        for fill in self.entry.fills:
            assign(message, fill.path, fill.value(self.arguments, self.names))
        return message

    def _run(self, ud: smach.UserData, inner: Any, sent: Any) -> str:
        gone = _gone.get(self.ros_name)
        if gone is not None and not self._back(inner):
            return self._fail(
                f"{self.entry.kind} {self.ros_name} is gone ({gone}); not waiting for it"
            )
        inner.recall_preempt()
        inner._path = self.path  # its log lines name this step's state (it is in no tree)
        with self._lock:
            self._inner = inner
        if self.preempt_requested():
            inner.request_preempt()
        local = smach.UserData()
        kind = self.entry.kind
        if kind == "action":
            ud.goal = message_data(sent)
            return self._action(ud, inner, sent, local)
        if kind == "service":
            ud.request = message_data(sent)
            return self._service(ud, inner, sent, local)
        return self._topic(ud, inner, local)

    def _back(self, inner: Any) -> bool:
        """Whether a server remembered as gone is in the ROS graph again (one look, and
        more for :data:`GONE_WAIT` seconds if that is set)."""
        deadline = time.monotonic() + GONE_WAIT
        while True:
            if _ready(inner):
                _gone.pop(self.ros_name, None)
                return True
            if time.monotonic() >= deadline or self.preempt_requested():
                return False
            time.sleep(0.05)

    def _action(self, ud: smach.UserData, inner: Any, goal: Any, local: smach.UserData) -> str:
        local["goal"] = goal
        local["feedback_sink"] = _FeedbackRecorder(ud, self.entry.feedback)
        outcome = inner.execute(local)
        local["feedback_sink"].flush()
        if outcome == "preempted":
            self.service_preempt()
            return "preempted"
        if "status" not in local:
            return self._no_answer(inner, "no result")
        status = _STATUS_NAMES.get(int(local["status"]), "aborted")
        result = local["answer"]
        ud.result = {"status": status, "result": message_data(result)}
        chosen = self._condition(result) or self.entry.status.get(status, "aborted")
        if outcome == "aborted" and status == "succeeded" and chosen == "succeeded":
            chosen = "aborted"  # the goal succeeded but the state failed after it
        return chosen

    def _service(self, ud: smach.UserData, inner: Any, request: Any, local: smach.UserData) -> str:
        local["request"] = request
        outcome = inner.execute(local)
        if outcome == "preempted":
            self.service_preempt()
            return "preempted"
        if "response" not in local:
            return self._no_answer(inner, "no response")
        response = local["response"]
        ud.response = message_data(response)
        return self._condition(response) or "succeeded"

    def _topic(self, ud: smach.UserData, inner: Any, local: smach.UserData) -> str:
        decided: list[tuple[str, Any]] = []

        def decide(message: Any) -> bool:
            """False (stop listening) once a message decides the outcome."""
            if not self.entry.conditions:
                decided.append(("succeeded", message))
                return False
            outcome = self._condition(message)
            if outcome is not None:
                decided.append((outcome, message))
            return outcome is None

        local["decide"] = decide
        outcome = inner.execute(local)
        if decided:
            chosen, message = decided[0]
            ud.message = message_data(message)
            return chosen
        if outcome == "preempted":
            self.service_preempt()
            return "preempted"
        smach.logerr(
            f"{self.path or 'RosCall'}: no message on {self.ros_name} "
            + ("" if not self.entry.conditions else "for which a condition of outcomes holds ")
            + f"within {self.entry.timeout} s (timeout)"
        )
        return "aborted"

    def _condition(self, message: Any) -> str | None:
        for outcome, condition in self.entry.conditions:
            if condition.holds(message, self.names):
                return outcome
        return None

    def _no_answer(self, inner: Any, what: str) -> str:
        if not _ready(inner):
            _gone[self.ros_name] = f"{what}: it left the ROS graph or never came"
        return "aborted"

    def _fail(self, message: str) -> str:
        smach.logerr(f"{self.path or 'RosCall'}: {message}")
        return "aborted"


class _FeedbackRecorder:
    """Writes feedback to ``ud.feedback``: the latest message, at most one record per
    :data:`FEEDBACK_PERIOD` (the last is written by :meth:`flush`)."""

    def __init__(self, ud: smach.UserData, mode: str | tuple[str, ...]) -> None:
        self.ud = ud
        self.mode = mode
        self.last = 0.0
        self.pending: Any = None

    def __call__(self, feedback: Any) -> None:
        if self.mode == "none":
            return
        if isinstance(self.mode, tuple):
            from plan_bridge.skills.ros.conditions import lookup

            data = {}
            for path in self.mode:
                try:
                    data[path] = message_data(lookup(feedback, path))
                except (AttributeError, IndexError):
                    data[path] = None
        else:
            data = message_data(feedback)
        now = time.monotonic()
        if now - self.last >= FEEDBACK_PERIOD:
            self.ud.feedback = data
            self.last, self.pending = now, None
        else:
            self.pending = data

    def flush(self) -> None:
        if self.pending is not None:
            self.ud.feedback = self.pending
            self.pending = None


def _ready(inner: Any) -> bool:
    """Whether the server of a smach.ros state is in the ROS graph (a topic: True)."""
    check: Callable[[], bool] | None = getattr(inner, "_server_ready", None) or getattr(
        inner, "_ready", None
    )
    return True if check is None else bool(check())


#: ROS name -> why its server is remembered as gone.
_gone: dict[str, str] = {}


def forget_servers() -> None:
    """Forget every server remembered as gone (tests; a robot restarted in-process)."""
    _gone.clear()


def _on_result(ud: smach.UserData, status: int, result: Any) -> None:
    ud["status"], ud["answer"] = status, result


def _on_feedback(ud: smach.UserData, feedback: Any) -> None:
    ud["feedback_sink"](feedback)


def _on_message(ud: smach.UserData, message: Any) -> bool:
    return bool(ud["decide"](message))


class _Pool:
    """smach.ros states kept for reuse, per node and ROS name (one per running step)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._idle: dict[tuple[Any, ...], list[Any]] = {}

    def _key(self, entry: RosEntry, name: str) -> tuple[Any, ...]:
        from smach.ros import default_node

        node = default_node()
        return (node, entry.key, name, entry.type_name, entry.timeout, entry.server_wait)

    def take(self, entry: RosEntry, name: str) -> Any:
        key = self._key(entry, name)
        with self._lock:
            idle = self._idle.get(key)
            if idle:
                return idle.pop()
        return _build(key[0], entry, name)

    def give(self, entry: RosEntry, name: str, inner: Any) -> None:
        key = self._key(entry, name)
        with self._lock:
            self._idle.setdefault(key, []).append(inner)


_pool = _Pool()


def _build(node: Any, entry: RosEntry, name: str) -> Any:
    from smach.ros import MonitorState, ServiceState, SimpleActionState

    if entry.kind == "action":
        return SimpleActionState(
            node,
            name,
            entry.interface,
            goal_key="goal",
            result_cb=_on_result,
            feedback_cb=_on_feedback,
            exec_timeout=entry.timeout,
            preempt_timeout=PREEMPT_TIMEOUT,
            server_wait_timeout=entry.server_wait,
        )
    if entry.kind == "service":
        return ServiceState(
            node,
            name,
            entry.interface,
            request_key="request",
            response_key="response",
            server_wait_timeout=entry.server_wait,
            call_timeout=entry.timeout,
        )
    return MonitorState(
        node, name, entry.interface, _on_message, max_checks=-1, timeout=entry.timeout
    )
