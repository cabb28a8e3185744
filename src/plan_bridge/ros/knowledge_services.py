"""A knowledge base over ROS 2: services shaped like PlanSys2's problem expert.

``KnowledgeServices(node, knowledge)`` (or ``RobotConnection.serve_knowledge``) offers
under ``NAME`` (default ``knowledge``, resolved against ``node``'s namespace):

=============================  ===========  ==============================================
service                        type         request -> response
=============================  ===========  ==============================================
``add_problem_instance``       BasicTypes   ``"leia robot"`` (or ``"leia - robot"``)
``remove_problem_instance``    BasicTypes   ``"leia"``; ``bool_value``: cascade (facts,
                                            values and goal atoms naming it go too)
``add_problem_predicate``      BasicTypes   ``"(robot_at leia kitchen)"`` (one or more)
``remove_problem_predicate``   BasicTypes   same
``add_problem_function``       BasicTypes   ``"(= (battery leia) 100)"`` (one or more)
``remove_problem_function``    BasicTypes   ``"(battery leia)"``
``set_problem_goal``           BasicTypes   ``"(and (robot_at leia bathroom))"``: the goal
``add_problem_goal``           BasicTypes   atoms that join the goal's conjunction
``remove_problem_goal``        BasicTypes   atoms that leave it; ``""``: the empty goal
``clear_problem_knowledge``    Trigger      every instance, fact, value and goal atom goes
``get_problem``                Trigger      ``message``: the problem as PDDL text
``get_problem_instances``      Trigger      ``message``: JSON ``{"leia": "robot", ...}``
``get_problem_predicates``     Trigger      JSON ``["(robot_at leia kitchen)", ...]``
``get_problem_functions``      Trigger      JSON ``[["(battery leia)", 100.0], ...]``
``get_problem_goal``           Trigger      JSON ``["(robot_at leia bathroom)", ...]``
=============================  ===========  ==============================================

``BasicTypes`` is ``test_msgs/srv/BasicTypes`` (text in ``string_value``), ``Trigger`` is
``std_srvs/srv/Trigger``, as in :mod:`plan_bridge.ros.protocol`: no message package
of our own. A change replies ``bool_value`` true and what changed (or that nothing
did) in ``string_value``; a refused one replies false and the knowledge base's error
(what is wrong, what is allowed). Every change is also published as JSON
(``{"version", "kind", "change", "source"}``, ``std_msgs/msg/String``, reliable and
transient local) on ``NAME/update_notify``, PlanSys2's notification topic.

Unlike PlanSys2, whose ``add_problem_goal`` replaces the goal, ``add_problem_goal``
adds atoms (ROSPlan's "add goal") and ``set_problem_goal`` replaces it. The services
live on smach's helper node and its executor thread (nothing needs to spin for
them); the knowledge base is thread-safe, and a mission that follows it
(``Executive.attach_knowledge``) replans when its objects or goal change.
"""

from __future__ import annotations

import importlib
import json
from collections.abc import Callable
from typing import Any

from plan_bridge.pddl.knowledge import (
    KnowledgeBase,
    KnowledgeChange,
    KnowledgeError,
    function_atom,
    goal_atoms,
    value_assignments,
)
from plan_bridge.pddl.task import format_fact

__all__ = ["KnowledgeServices"]

#: The longest request text a service accepts (characters).
MAX_REQUEST = 64 * 1024


class KnowledgeServices:
    """The knowledge base services of one node (see the module documentation)."""

    def __init__(
        self, node: Any, knowledge: KnowledgeBase, *, name: str = "knowledge", source: str = "ros"
    ) -> None:
        # smach.ros.rclpy_api loads rclpy with its one known warning silenced.
        from smach.ros.executor import SmachExecutor, publisher_events
        from smach.ros.rclpy_api import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        basic = importlib.import_module("test_msgs.srv").BasicTypes
        trigger = importlib.import_module("std_srvs.srv").Trigger
        self._string = importlib.import_module("std_msgs.msg").String
        self.knowledge = knowledge
        self.source = source
        self._helper = SmachExecutor.for_node(node)
        helper = self._helper.node
        base = node.resolve_service_name(name).rstrip("/")
        #: Service name (``add_problem_instance``) -> its full ROS name.
        self.names: dict[str, str] = {}
        self._services: list[Any] = []
        changes: dict[str, Callable[[Any], str]] = {
            "add_problem_instance": self._add_instance,
            "remove_problem_instance": self._remove_instance,
            "add_problem_predicate": lambda r: self._facts(r, add=True),
            "remove_problem_predicate": lambda r: self._facts(r, add=False),
            "add_problem_function": self._add_values,
            "remove_problem_function": self._remove_values,
            "set_problem_goal": self._set_goal,
            "add_problem_goal": self._add_goal,
            "remove_problem_goal": self._remove_goal,
        }
        gets: dict[str, Callable[[], str]] = {
            "clear_problem_knowledge": self._clear,
            "get_problem": knowledge.problem_pddl,
            "get_problem_instances": lambda: json.dumps(knowledge.instances),
            "get_problem_predicates": lambda: json.dumps(knowledge.to_json()["facts"]),
            "get_problem_functions": lambda: json.dumps(knowledge.to_json()["values"]),
            "get_problem_goal": lambda: json.dumps([format_fact(g) for g in knowledge.goal]),
        }
        group = self._helper.callback_group
        for service, change in changes.items():
            self.names[service] = f"{base}/{service}"
            self._services.append(
                helper.create_service(
                    basic, self.names[service], self._basic(change), callback_group=group
                )
            )
        for service, answer in gets.items():
            self.names[service] = f"{base}/{service}"
            self._services.append(
                helper.create_service(
                    trigger, self.names[service], self._trigger(answer), callback_group=group
                )
            )
        self.notify_topic = f"{base}/update_notify"
        qos = QoSProfile(
            depth=10,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self._publisher = helper.create_publisher(
            self._string,
            self.notify_topic,
            qos,
            event_callbacks=publisher_events(self.notify_topic),
        )
        knowledge.add_listener(self._publish)

    def close(self) -> None:
        """Remove the services and the topic."""
        self.knowledge.remove_listener(self._publish)
        node = self._helper.node
        if self._helper.alive:
            for service in self._services:
                node.destroy_service(service)
            node.destroy_publisher(self._publisher)
        self._services = []

    # -- callbacks (smach's executor threads) ------------------------------------------------
    def _basic(self, change: Callable[[Any], str]) -> Callable[[Any, Any], Any]:
        def callback(request: Any, response: Any) -> Any:
            response.bool_value, response.string_value = self._answer(lambda: change(request))
            return response

        return callback

    def _trigger(self, answer: Callable[[], str]) -> Callable[[Any, Any], Any]:
        def callback(request: Any, response: Any) -> Any:
            response.success, response.message = self._answer(answer)
            return response

        return callback

    def _answer(self, work: Callable[[], str]) -> tuple[bool, str]:
        try:
            return True, work()
        except (KnowledgeError, ValueError) as exc:
            return False, str(exc)
        except Exception as exc:  # a bug must not stop the executor thread
            return False, f"internal error: {type(exc).__name__}: {exc}"

    def _publish(self, change: KnowledgeChange) -> None:
        message = self._string()
        message.data = json.dumps(
            {
                "version": change.version,
                "kind": change.kind,
                "change": change.description,
                "source": change.source,
            }
        )
        self._publisher.publish(message)

    # -- the changes ----------------------------------------------------------------------
    def _text(self, request: Any) -> str:
        text = str(request.string_value)
        if len(text) > MAX_REQUEST:
            raise KnowledgeError(f"a request is at most {MAX_REQUEST} characters")
        return text

    def _done(self, changed: object, what: str, unchanged: str = "") -> str:
        if changed:
            return f"{what} (version {self.knowledge.version})"
        return f"nothing changed: {unchanged or what}"

    def _add_instance(self, request: Any) -> str:
        words = self._text(request).split()
        if len(words) == 3 and words[1] == "-":
            words = [words[0], words[2]]
        if len(words) not in (1, 2):
            raise KnowledgeError(
                f"add_problem_instance: expected 'NAME TYPE' (e.g. 'leia robot'), got "
                f"{request.string_value!r}"
            )
        name, kind = words[0], words[1] if len(words) == 2 else "object"
        added = self.knowledge.add_instance(name, kind, source=self.source)
        return self._done(added, f"instance {name.lower()} - {kind.lower()}")

    def _remove_instance(self, request: Any) -> str:
        words = self._text(request).split()
        if len(words) != 1:
            raise KnowledgeError(
                f"remove_problem_instance: expected one instance name, got {request.string_value!r}"
            )
        cascade = bool(request.bool_value)
        self.knowledge.remove_instance(words[0], cascade=cascade, source=self.source)
        return self._done(True, f"instance {words[0].lower()} removed")

    def _facts(self, request: Any, *, add: bool) -> str:
        atoms = goal_atoms(self._text(request))
        if not atoms:
            raise KnowledgeError("expected one or more atoms like (robot_at leia kitchen)")
        change = self.knowledge.add_facts if add else self.knowledge.remove_facts
        changed = change(atoms, source=self.source)
        verb, state = ("added", "true") if add else ("removed", "false")
        return self._done(
            changed,
            f"{verb}: {' '.join(map(format_fact, changed))}",
            f"{' '.join(map(format_fact, atoms))} already {state}",
        )

    def _add_values(self, request: Any) -> str:
        values = value_assignments(self._text(request))
        changed = self.knowledge.set_values(values, source=self.source)
        shown = " ".join(format_fact(atom) for atom in changed or [a for a, _ in values])
        return self._done(changed, f"set: {shown}", f"{shown} already had these values")

    def _remove_values(self, request: Any) -> str:
        atom = function_atom(self._text(request))
        removed = self.knowledge.remove_value(atom, source=self.source)
        return self._done(
            removed, f"removed the value of {format_fact(atom)}", f"{format_fact(atom)} had none"
        )

    def _set_goal(self, request: Any) -> str:
        changed = self.knowledge.set_goal(self._text(request), source=self.source)
        return self._done(changed, f"goal {_goal_text(self.knowledge)}")

    def _add_goal(self, request: Any) -> str:
        added = self.knowledge.add_goal(self._text(request), source=self.source)
        return self._done(added, f"goal {_goal_text(self.knowledge)}")

    def _remove_goal(self, request: Any) -> str:
        text = self._text(request)
        if text.strip():
            changed: object = self.knowledge.remove_goal(text, source=self.source)
        else:
            changed = self.knowledge.clear_goal(source=self.source)
        return self._done(changed, f"goal {_goal_text(self.knowledge)}")

    def _clear(self) -> str:
        return self._done(self.knowledge.clear(source=self.source), "the problem is empty")


def _goal_text(knowledge: KnowledgeBase) -> str:
    return "(and" + "".join(" " + format_fact(g) for g in knowledge.goal) + ")"
