"""The one generic interface between the executive and a skill server.

Only message packages that ship as PyPI wheels are used: ``test_msgs`` (stable
across ROS 2 releases) and ``std_srvs``. Their only action types are
``Fibonacci`` (an ``int32`` goal, ``int32[]`` feedback and result) and
``NestedMessage`` (numbers and times, no strings), so no action can carry
"action name + string arguments -> outcome + observations" by itself, and there is
no ``example_interfaces`` or ``smach_msgs`` wheel. Building our own interface
package needs the ROS build toolchain. So one skill is three calls, all under
``<prefix>``:

1. ``submit`` (``test_msgs/srv/BasicTypes``): ``request.string_value`` is the ground
   action in PDDL text, ``"(pick robot1 cup kitchen)"``; ``response.int64_value``
   is a ticket (> 0), or 0 with the reason in ``response.string_value``;
2. ``<action>`` (``test_msgs/action/Fibonacci``, one ROS action per PDDL action,
   named by :func:`action_topic`: ``switch-on`` is served as ``<prefix>/switch_on``):
   ``goal.order`` is the ticket; feedback ``sequence`` is ``[percent done]``; the goal
   ends SUCCEEDED, ABORTED (the action failed) or CANCELED (preempted: the world is
   unchanged);
3. ``report`` (``test_msgs/srv/BasicTypes``): ``request.int64_value`` is the ticket;
   ``response.string_value`` is the JSON object ``{"outcome": "succeeded" | "aborted",
   "observations": [["(at robot1 hall)", true], ["(battery-level robot1)", 42.5], ...],
   "detail": "..."}`` (a numeric fluent is observed with a number).

``perform`` (``BasicTypes``) does all three in one service, for the service
transport: ``request.string_value`` is the ground action, ``request.int64_value`` a
request id the client draws per execution, ``request.float64_value`` how long the
server may hold the call (seconds, at most :data:`MAX_PERFORM_HOLD`). The first
request with an id starts the action; the reply comes when it ends or when the hold
passes: ``response.int64_value`` is :data:`PERFORM_DONE` (``bool_value`` and the JSON
result in ``string_value``, as ``report``) or :data:`PERFORM_RUNNING`. The client asks
again with the same id until done; a repeated id never runs the action twice. So a
reply lost on the way (Fast DDS drops one when the server has not yet matched a new
client's reply reader) costs one resend, never a mission.
``heartbeat`` (topic, ``std_msgs/String``: a counter) is published by the robot node
every :data:`HEARTBEAT_PERIOD` seconds; an executive that heard it and then hears
nothing for :data:`HEARTBEAT_TIMEOUT` seconds takes the robot for gone, whatever the
DDS lease of the robot's process (its own check, the same on every middleware). Id 0 performs at once and
replies when done (one blocking call). ``facts`` (``std_srvs/Trigger``) returns
the JSON list of the facts true in the simulated world; ``info`` (``Trigger``) returns
a JSON object describing the robot node (see :func:`task_digest` and
``SkillServer.info``). A robot node that runs a domain's own skills (a domain folder)
streams feedback ``sequence = [states entered so far]`` instead of a percentage. Payloads are text and JSON:
parsed, bounded and validated, never evaluated.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import math
import re
import threading
from collections.abc import Iterable
from typing import Any

from plan_bridge.pddl.task import Fact, PlanningTask, format_fact, parse_fact

__all__ = [
    "FACTS_SERVICE",
    "HEARTBEAT_PERIOD",
    "HEARTBEAT_TIMEOUT",
    "HEARTBEAT_TOPIC",
    "INFO_SERVICE",
    "MAX_PAYLOAD",
    "MAX_PERFORM_HOLD",
    "PERFORM_DONE",
    "PERFORM_HOLD",
    "PERFORM_RUNNING",
    "PERFORM_SERVICE",
    "REPORT_SERVICE",
    "SUBMIT_SERVICE",
    "Performance",
    "action_topic",
    "decode_observations",
    "decode_result",
    "encode_observations",
    "encode_result",
    "interfaces",
    "task_digest",
]

#: Service names below the prefix.
SUBMIT_SERVICE = "submit"
REPORT_SERVICE = "report"
PERFORM_SERVICE = "perform"
FACTS_SERVICE = "facts"
INFO_SERVICE = "info"
#: Topic below the prefix: the robot node's heartbeat, every HEARTBEAT_PERIOD s.
HEARTBEAT_TOPIC = "heartbeat"
HEARTBEAT_PERIOD = 0.25
#: Silence (s) after which an executive that heard the heartbeat takes the robot for
#: gone: twelve beats, room for a robot process starved of CPU for a while.
HEARTBEAT_TIMEOUT = 3.0
#: ``perform`` replies: ``response.int64_value`` is one of these.
PERFORM_RUNNING = 0
PERFORM_DONE = 1
#: How long a client lets the server hold a ``perform`` call (s), and the most a server holds.
PERFORM_HOLD = 1.0
MAX_PERFORM_HOLD = 30.0
#: Largest result payload a client accepts (bytes of JSON).
MAX_PAYLOAD = 1_000_000


def action_topic(prefix: str, action: str) -> str:
    """The ROS action name of a PDDL action: ``PREFIX/ACTION`` with every character
    ROS names do not allow (PDDL allows ``-``) replaced by ``_``."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", action)
    if name[:1].isdigit():
        name = "_" + name
    return f"{prefix.rstrip('/')}/{name}"


def encode_result(
    ok: bool, observations: Iterable[tuple[Fact, bool | float]], detail: str = ""
) -> str:
    return json.dumps(
        {
            "outcome": "succeeded" if ok else "aborted",
            "observations": encode_observations(observations),
            "detail": detail,
        }
    )


def encode_observations(observations: Iterable[tuple[Fact, bool | float]]) -> list[list[Any]]:
    """Observations as JSON: ``[fact text, true/false]``, a numeric fluent's reading as
    ``[atom text, number]`` (always with a fraction, see :func:`decode_observations`)."""
    return [
        [format_fact(fact), truth if isinstance(truth, bool) else float(truth)]
        for fact, truth in observations
    ]


def decode_result(text: str) -> tuple[str, list[tuple[Fact, bool | float]], str]:
    """(outcome, observations, detail) from a result payload; ValueError if malformed
    (the observations as :func:`decode_observations` reads them)."""
    if not isinstance(text, str) or len(text) > MAX_PAYLOAD:
        raise ValueError("the result payload is not a string of bounded size")
    data: Any = json.loads(text)
    if not isinstance(data, dict):
        raise ValueError("the result payload is not a JSON object")
    outcome = data.get("outcome")
    if outcome not in ("succeeded", "aborted"):
        raise ValueError(f"the result outcome {outcome!r} is not succeeded or aborted")
    observations = decode_observations(data.get("observations", []))
    detail = data.get("detail", "")
    return outcome, observations, str(detail)[:1000]


def decode_observations(raw: Any) -> list[tuple[Fact, bool | float]]:
    """The observations of :func:`encode_observations`' JSON; ValueError if malformed.

    An observation is ``[fact, true/false]``, or ``[atom, number]`` for a numeric
    fluent's reading (``["(battery-level robot)", 20.9]``): a finite JSON number with a
    fraction or exponent (``1`` is refused: a truth written as a number is a mistake,
    not a reading).
    """
    if not isinstance(raw, list):
        raise ValueError("observations must be a list of [fact, true/false] pairs")
    observations: list[tuple[Fact, bool | float]] = []
    for item in raw:
        if (
            not isinstance(item, list)
            or len(item) != 2
            or not isinstance(item[0], str)
            or not (
                isinstance(item[1], bool) or (isinstance(item[1], float) and math.isfinite(item[1]))
            )
        ):
            raise ValueError(
                f"observation {item!r} is not a [fact, true/false] pair "
                f"(nor [atom, number] for a numeric fluent)"
            )
        observations.append((parse_fact(item[0]), item[1]))
    return observations


def task_digest(task: PlanningTask) -> str:
    """A short fingerprint of a task's objects, initial state, goal and actions.

    The executive compares it with the robot node's (``info``) so that both sides
    are sure to run the same problem.
    """
    data = {
        "objects": sorted(task.objects.items()),
        "init": sorted(format_fact(f) for f in task.initial_facts),
        "goal": sorted(format_fact(f) for f in task.goal_facts),
        "actions": sorted(task.actions),
    }
    return hashlib.sha256(json.dumps(data).encode()).hexdigest()[:16]


def interfaces() -> tuple[Any, Any, Any]:
    """The message types: (Fibonacci action, BasicTypes service, Trigger service)."""
    import smach.ros.rclpy_api  # noqa: F401  (loads rclpy with its one known warning silenced)

    fibonacci = importlib.import_module("test_msgs.action").Fibonacci
    basic_types = importlib.import_module("test_msgs.srv").BasicTypes
    trigger = importlib.import_module("std_srvs.srv").Trigger
    return fibonacci, basic_types, trigger


class Performance:
    """The server's record of one ``perform`` request id: its action text and, once
    the action ended, its outcome and JSON result (as ``report`` gives it)."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.done = threading.Event()
        self.ok = False
        self.result = ""

    def finish(self, ok: bool, result: str) -> None:
        """Record the outcome and the JSON result payload; wakes every waiting request."""
        self.ok = ok
        self.result = result
        self.done.set()

    def refuse(self, reason: str) -> None:
        self.finish(False, encode_result(False, [], reason))
