"""Size a port from the original SMACH: what in a program changes or behaves differently.

``python -m smach.port_check FILE...`` reads SMACH programs (it never runs or
imports them) and lists, with line numbers:

* ``rospy`` / ``roslib`` / ``rostest`` uses, each with its rclpy equivalent;
* actionlib and ROS 1 message/service idioms (``FooAction``/``FooGoal`` from
  ``pkg.msg``, ``FooRequest``, ``actionlib.SimpleActionServer``, ``GoalStatus`` codes);
* userdata the strict mode rejects: writes to keys not declared as outputs, reads of
  keys not declared as inputs, writes into objects read through input-only keys;
* construction the strict mode rejects: transitions to labels that are neither a
  state nor a container outcome (an error at the end of the ``with`` block),
  outcomes given as a bare string;
* names that moved or do not exist here (``smach_msgs``, ``smach_ros.util``, ...).

Each finding has a kind: ``change`` (the program fails until edited), ``differs``
(it runs, with a documented difference) or ``note``. The exit status is 1 if any
``change`` was found, 2 if a file could not be read, else 0. The checks are static
and literal: keys or labels built at run time are not followed. Every difference
is explained in docs/porting-from-smach.md.

(Over 600 lines: the rule tables and the walk that applies
them are read together; splitting them would only add an import.)
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import sys
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

__all__ = ["Finding", "check_file", "check_source", "main"]

CHANGE, DIFFERS, NOTE = "change", "differs", "note"


@dataclass(frozen=True, order=True)
class Finding:
    """One thing to look at when porting: where, what kind, why, and what to write instead."""

    file: str
    line: int
    col: int
    kind: str  # change | differs | note
    topic: str  # rospy | actionlib | userdata | construction | moved | syntax
    message: str
    suggestion: str = ""

    def format(self) -> str:
        text = f"{self.file}:{self.line}:{self.col}: {self.kind} [{self.topic}] {self.message}"
        return f"{text}\n    -> {self.suggestion}" if self.suggestion else text


#: rospy name -> (kind, rclpy equivalent). ``node`` is your rclpy node.
ROSPY: dict[str, tuple[str, str]] = {
    "init_node": (CHANGE, "rclpy.init(); node = rclpy.create_node(NAME)"),
    "spin": (CHANGE, "rclpy.spin(node) (smach states do not need your node spun)"),
    "is_shutdown": (CHANGE, "not rclpy.ok()"),
    "sleep": (CHANGE, "time.sleep(seconds), or self.sleep(seconds) in a state (preemptable)"),
    "Duration": (CHANGE, "rclpy.duration.Duration(seconds=S), or plain float seconds"),
    "Time": (CHANGE, "node.get_clock().now() / rclpy.time.Time"),
    "get_rostime": (CHANGE, "node.get_clock().now()"),
    "get_time": (CHANGE, "node.get_clock().now().nanoseconds / 1e9"),
    "Rate": (CHANGE, "node.create_rate(hz) (needs the node spun), or time.sleep(1 / hz)"),
    "loginfo": (CHANGE, "node.get_logger().info(msg), or smach.loginfo(msg)"),
    "logwarn": (CHANGE, "node.get_logger().warning(msg), or smach.logwarn(msg)"),
    "logerr": (CHANGE, "node.get_logger().error(msg), or smach.logerr(msg)"),
    "logdebug": (CHANGE, "node.get_logger().debug(msg), or smach.logdebug(msg)"),
    "logfatal": (CHANGE, "node.get_logger().fatal(msg)"),
    "Publisher": (CHANGE, "node.create_publisher(MsgType, topic, queue_size)"),
    "Subscriber": (CHANGE, "node.create_subscription(MsgType, topic, callback, 10)"),
    "Service": (
        CHANGE,
        "node.create_service(SrvType, name, handler); handler(request, response) fills "
        "and returns response",
    ),
    "ServiceProxy": (CHANGE, "node.create_client(SrvType, name) and client.call_async(request)"),
    "wait_for_service": (CHANGE, "client.wait_for_service(timeout_sec=...)"),
    "wait_for_message": (
        CHANGE,
        "rclpy.wait_for_message.wait_for_message(MsgType, node, topic)",
    ),
    "get_param": (CHANGE, "node.declare_parameter(name, default).value"),
    "set_param": (CHANGE, "node.set_parameters([rclpy.parameter.Parameter(name, value=v)])"),
    "has_param": (CHANGE, "node.has_parameter(name)"),
    "on_shutdown": (CHANGE, "rclpy.get_default_context().on_shutdown(callback)"),
    "signal_shutdown": (CHANGE, "rclpy.shutdown()"),
    "get_name": (CHANGE, "node.get_name()"),
    "ROSInterruptException": (
        CHANGE,
        "KeyboardInterrupt / rclpy.executors.ExternalShutdownException",
    ),
    "ServiceException": (CHANGE, "check the future of client.call_async(request)"),
}

#: Module -> (kind, message, suggestion) for imports.
MODULES: dict[str, tuple[str, str, str]] = {
    "rospy": (CHANGE, "rospy is ROS 1", "import rclpy"),
    "roslib": (CHANGE, "roslib.load_manifest is ROS 1 (rosbuild)", "delete the line"),
    "rostest": (CHANGE, "rostest is ROS 1", "run the test with pytest (launch_testing for graphs)"),
    "rosunit": (CHANGE, "rosunit is ROS 1", "run the test with pytest"),
    "actionlib": (
        CHANGE,
        "actionlib is ROS 1",
        "rclpy.action.ActionServer(node, Action, name, execute_callback) / "
        "rclpy.action.ActionClient(node, Action, name); smach_ros.SimpleActionState and "
        "ActionServerWrapper wrap them",
    ),
    "actionlib_msgs": (
        CHANGE,
        "actionlib_msgs is ROS 1; GoalStatus codes differ in ROS 2 "
        "(SUCCEEDED 3->4, ABORTED 4->6, PREEMPTED 2 -> CANCELED 5)",
        "from action_msgs.msg import GoalStatus",
    ),
    "smach_msgs": (
        CHANGE,
        "smach_msgs is not used: introspection publishes JSON on std_msgs/String",
        "read it with smach_ros.IntrospectionClient or the smach-viewer command",
    ),
    "smach_viewer": (
        DIFFERS,
        "the ROS smach_viewer cannot read these topics",
        "use the smach-viewer command (docs/introspection.md)",
    ),
}

#: actionlib GoalStatus constant -> action_msgs spelling (the numbers differ too).
GOAL_STATUS = {
    "PENDING": "STATUS_ACCEPTED",
    "ACTIVE": "STATUS_EXECUTING",
    "PREEMPTING": "STATUS_CANCELING",
    "RECALLING": "STATUS_CANCELING",
    "PREEMPTED": "STATUS_CANCELED",
    "RECALLED": "STATUS_CANCELED",
    "SUCCEEDED": "STATUS_SUCCEEDED",
    "ABORTED": "STATUS_ABORTED",
    "LOST": "STATUS_UNKNOWN",
}

#: smach_ros submodules of the originals -> where their names are here.
MOVED_MODULES = {
    "smach_ros.util": "smach_ros (set_preempt_handler)",
    "smach_ros.introspection": "smach_ros (IntrospectionServer, IntrospectionClient)",
    "smach_ros.simple_action_state": "smach_ros (SimpleActionState)",
    "smach_ros.service_state": "smach_ros (ServiceState)",
    "smach_ros.monitor_state": "smach_ros (MonitorState)",
    "smach_ros.condition_state": "smach_ros (ConditionState)",
    "smach_ros.action_server_wrapper": "smach_ros (ActionServerWrapper)",
    "smach_ros.node": "smach_ros (SmachNode)",
    "smach_ros.ros_state": "smach_ros (RosState)",
}

STATE_BASES = {"State", "RosState"}
NODE_STATES = {
    "SimpleActionState",
    "ServiceState",
    "MonitorState",
    "ConditionState",
    "ActionServerWrapper",
}


@dataclass
class _Interface:
    """The keys a state or callback declares (None: not known statically)."""

    inputs: set[str] | None = field(default_factory=set)
    outputs: set[str] | None = field(default_factory=set)


def _strings(node: ast.expr | None) -> set[str] | None:
    """The strings of a literal list/tuple/set (None if not a literal of strings)."""
    if node is None:
        return set()
    if isinstance(node, ast.List | ast.Tuple | ast.Set):
        out = set()
        for element in node.elts:
            if not (isinstance(element, ast.Constant) and isinstance(element.value, str)):
                return None
            out.add(element.value)
        return out
    if isinstance(node, ast.Constant) and node.value is None:
        return set()
    return None


def _name_of(func: ast.expr) -> str:
    """``a.b.C`` -> ``C``; ``C`` -> ``C``."""
    if isinstance(func, ast.Attribute):
        return func.attr
    if isinstance(func, ast.Name):
        return func.id
    return ""


def _dotted(node: ast.expr) -> str:
    if isinstance(node, ast.Attribute):
        inner = _dotted(node.value)
        return f"{inner}.{node.attr}" if inner else ""
    if isinstance(node, ast.Name):
        return node.id
    return ""


def _interface_from_call(call: ast.Call, positional: Sequence[str]) -> _Interface:
    """Keys from ``State.__init__``-like arguments (positional names given in order)."""
    args: dict[str, ast.expr] = {}
    for name, value in zip(positional, call.args, strict=False):
        args[name] = value
    for keyword in call.keywords:
        if keyword.arg:
            args[keyword.arg] = keyword.value
    inputs, outputs, io = (
        _strings(args.get("input_keys")),
        _strings(args.get("output_keys")),
        _strings(args.get("io_keys")),
    )
    return _Interface(
        None if inputs is None or io is None else inputs | io,
        None if outputs is None or io is None else outputs | io,
    )


class _Checker(ast.NodeVisitor):
    def __init__(self, filename: str) -> None:
        self.filename = filename
        self.findings: list[Finding] = []
        self.rospy_names: set[str] = set()  # local names bound to the rospy module
        self.action_imports: dict[str, str] = {}  # local name -> ROS 2 spelling
        self.callback_interfaces: dict[str, _Interface] = {}
        self.functions: dict[str, ast.FunctionDef] = {}
        self.cbstates: list[tuple[str, _Interface]] = []
        self.machines: dict[str, set[str]] = {}  # name -> outcomes, of literal StateMachines

    def add(self, node: ast.AST, kind: str, topic: str, message: str, suggestion: str = "") -> None:
        line = getattr(node, "lineno", 1)
        col = getattr(node, "col_offset", 0) + 1
        self.findings.append(Finding(self.filename, line, col, kind, topic, message, suggestion))

    # -- imports -------------------------------------------------------------------------------
    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            self._module(node, alias.name)
            if alias.name == "rospy":
                self.rospy_names.add(alias.asname or "rospy")

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        module = node.module or ""
        self._module(node, module)
        if module == "rospy":
            for alias in node.names:
                entry = ROSPY.get(alias.name)
                self.add(
                    node,
                    CHANGE,
                    "rospy",
                    f"'{alias.name}' imported from rospy",
                    entry[1] if entry else "see the rclpy documentation",
                )
        parts = module.split(".")
        if len(parts) == 2 and parts[1] in ("msg", "srv"):
            self._ros1_interfaces(node, parts[0], parts[1])

    def _module(self, node: ast.AST, module: str) -> None:
        top = module.split(".", maxsplit=1)[0]
        entry = MODULES.get(top)
        if entry is not None:
            kind, message, suggestion = entry
            self.add(
                node,
                kind,
                "actionlib" if top.startswith("actionlib") else top if top == "rospy" else "moved",
                message,
                suggestion,
            )
        moved = MOVED_MODULES.get(module)
        if moved is not None:
            self.add(
                node,
                CHANGE,
                "moved",
                f"module {module} does not exist here",
                f"import from {moved}",
            )

    def _ros1_interfaces(self, node: ast.ImportFrom, package: str, kind: str) -> None:
        names = [alias.name for alias in node.names]
        actions = {n[: -len("Action")] for n in names if n.endswith("Action") and len(n) > 6}
        for name in names:
            if kind == "msg":
                for suffix in (
                    "ActionGoal",
                    "ActionResult",
                    "ActionFeedback",
                    "Action",
                    "Goal",
                    "Result",
                    "Feedback",
                ):
                    base = name[: -len(suffix)]
                    if (
                        name.endswith(suffix)
                        and base
                        and (suffix.startswith("Action") or base in actions)
                    ):
                        spelled = (
                            base
                            if suffix == "Action"
                            else f"{base}.{suffix.removeprefix('Action')}"
                        )
                        self.action_imports[name] = spelled
                        self.add(
                            node,
                            CHANGE,
                            "actionlib",
                            f"{name} from {package}.msg is a ROS 1 action type",
                            f"from {package}.action import {base}; use {spelled}",
                        )
                        break
            else:
                for suffix in ("Request", "Response"):
                    base = name[: -len(suffix)]
                    if name.endswith(suffix) and base:
                        self.action_imports[name] = f"{base}.{suffix}"
                        self.add(
                            node,
                            CHANGE,
                            "rospy",
                            f"{name} from {package}.srv is ROS 1 spelling",
                            f"from {package}.srv import {base}; use {base}.{suffix}",
                        )
                        break

    # -- rospy / actionlib uses ----------------------------------------------------------------------
    def visit_Attribute(self, node: ast.Attribute) -> None:
        if isinstance(node.value, ast.Name) and node.value.id in self.rospy_names:
            kind, suggestion = ROSPY.get(node.attr, (CHANGE, "see the rclpy documentation"))
            self.add(node, kind, "rospy", f"rospy.{node.attr} is ROS 1", suggestion)
        elif (
            _dotted(node).endswith(f"GoalStatus.{node.attr}")
            and node.attr.isupper()
            and not node.attr.startswith("STATUS_")
        ):
            spelled = GOAL_STATUS.get(node.attr)
            self.add(
                node,
                CHANGE,
                "actionlib",
                f"GoalStatus.{node.attr} is the ROS 1 (actionlib) spelling and code",
                f"GoalStatus.{spelled} (action_msgs)"
                if spelled
                else "no ROS 2 equivalent: rejection is the goal response, not a status",
            )
        self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> None:
        spelled = self.action_imports.get(node.id)
        if spelled is not None and isinstance(node.ctx, ast.Load):
            self.add(node, CHANGE, "actionlib", f"{node.id} is the ROS 1 spelling", spelled)

    # -- states, callbacks and construction ----------------------------------------------------------
    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        bases = {_name_of(base) for base in node.bases}
        if bases & STATE_BASES:
            interface = self._class_interface(node)
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and item.name == "execute":
                    self._check_userdata(item, interface, f"state class {node.name}")
        self.generic_visit(node)

    def _class_interface(self, node: ast.ClassDef) -> _Interface:
        for item in node.body:
            if not (isinstance(item, ast.FunctionDef) and item.name == "__init__"):
                continue
            for call in ast.walk(item):
                if not (isinstance(call, ast.Call) and _name_of(call.func) == "__init__"):
                    continue
                owner = call.func.value if isinstance(call.func, ast.Attribute) else None
                explicit_self = isinstance(owner, ast.Name) and owner.id in STATE_BASES
                explicit_self |= isinstance(owner, ast.Attribute) and owner.attr in STATE_BASES
                args = ast.Call(
                    call.func, call.args[1:] if explicit_self else call.args, call.keywords
                )
                return _interface_from_call(
                    args, ("outcomes", "input_keys", "output_keys", "io_keys")
                )
        return _Interface()

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        self.functions.setdefault(node.name, node)
        for decorator in node.decorator_list:
            if isinstance(decorator, ast.Call) and _name_of(decorator.func) == "cb_interface":
                self.callback_interfaces[node.name] = _interface_from_call(
                    decorator, ("outcomes", "input_keys", "output_keys")
                )
        self.generic_visit(node)

    def visit_Assign(self, node: ast.Assign) -> None:
        value = node.value
        if isinstance(value, ast.Call) and _name_of(value.func) in ("StateMachine", "Sequence"):
            outcomes = _strings(value.args[0] if value.args else _keyword(value, "outcomes"))
            for target in node.targets:
                if isinstance(target, ast.Name) and outcomes is not None:
                    self.machines[target.id] = outcomes
        self.generic_visit(node)

    def visit_With(self, node: ast.With) -> None:
        for item in node.items:
            expr = item.context_expr
            if isinstance(expr, ast.Call) and _name_of(expr.func) == "opened":
                expr = expr.func.value if isinstance(expr.func, ast.Attribute) else expr
            if isinstance(expr, ast.Name) and expr.id in self.machines:
                self._check_transitions(expr.id, node.body)
        self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> None:
        name = _name_of(node.func)
        if name == "CBState" and node.args and isinstance(node.args[0], ast.Name):
            declared = _interface_from_call(
                node,
                ("cb", "cb_args", "cb_kwargs", "outcomes", "input_keys", "output_keys", "io_keys"),
            )
            self.cbstates.append((node.args[0].id, declared))
        elif name in NODE_STATES and node.args and _looks_ros1(name, node.args[0]):
            self.add(
                node,
                NOTE,
                "rospy",
                f"{name} without a node (ROS 1 signature): it runs on the default node "
                "(rclpy initialised on demand)",
                "pass your node first to resolve names in its namespace",
            )
        elif name == "IntrospectionServer":
            self.add(
                node,
                DIFFERS,
                "moved",
                "IntrospectionServer publishes JSON on std_msgs/String and is itself an rclpy "
                "node named after the server (rclpy initialised on demand)",
                "view it with the smach-viewer command (docs/introspection.md)",
            )
        for keyword in node.keywords:
            value = keyword.value
            if (
                keyword.arg == "outcomes"
                and isinstance(value, ast.Constant)
                and isinstance(value.value, str)
            ):
                self.add(
                    value,
                    CHANGE,
                    "construction",
                    f"outcomes={value.value!r} is a bare string (the original split it into "
                    "characters); it is refused",
                    f"outcomes=[{value.value!r}]",
                )
        self.generic_visit(node)

    # -- after the walk: checks that need the whole file -------------------------------------------
    def finish(self) -> None:
        checked: set[str] = set()
        for function, declared in self.cbstates:
            node = self.functions.get(function)
            if node is None:
                continue
            interface = _union(declared, self.callback_interfaces.get(function, _Interface()))
            self._check_userdata(node, interface, f"callback {function} (CBState)")
            checked.add(function)
        for function, interface in self.callback_interfaces.items():
            if function not in checked and function in self.functions:
                self._check_userdata(self.functions[function], interface, f"callback {function}")
        unique = sorted(set(self.findings))
        self.findings = unique

    def _check_transitions(self, machine: str, body: list[ast.stmt]) -> None:
        labels: set[str] = set()
        targets: list[tuple[ast.Constant, str]] = []
        for call in _calls_outside_nested_withs(body, set(self.machines)):
            if _name_of(call.func) not in ("add", "add_auto") or not call.args:
                continue
            label = call.args[0]
            if isinstance(label, ast.Constant) and isinstance(label.value, str):
                labels.add(label.value)
            table = call.args[2] if len(call.args) > 2 else _keyword(call, "transitions")
            if isinstance(table, ast.Dict):
                for value in table.values:
                    if isinstance(value, ast.Constant) and isinstance(value.value, str):
                        targets.append((value, value.value))
        allowed = labels | self.machines[machine]
        for node, target in targets:
            if target and target not in allowed:
                self.add(
                    node,
                    CHANGE,
                    "construction",
                    f"transition to {target!r}, which is neither a state of {machine} nor one of "
                    "its outcomes: the original logged it and failed at execute(); here the "
                    f"end of the 'with {machine}:' block raises InvalidTransitionError",
                    f"add a state labelled {target!r}, add {target!r} to {machine}'s outcomes, "
                    f"or use one of: {', '.join(sorted(allowed))}",
                )

    def _check_userdata(self, function: ast.FunctionDef, interface: _Interface, what: str) -> None:
        params = [a.arg for a in function.args.args]
        if params and params[0] == "self":
            params = params[1:]
        if not params:
            return
        ud = params[0]
        for node in ast.walk(function):
            key, store, nested = _userdata_access(node, ud)
            if key is None:
                continue
            outputs, inputs = interface.outputs, interface.inputs
            if store and outputs is not None and key not in outputs:
                if nested:
                    message = (
                        f"{what} modifies an object read through input-only key '{key}': the "
                        "original wrote to a throw-away wrapper, strict mode raises "
                        "InvalidUserCodeError"
                    )
                    suggestion = f"declare '{key}' in io_keys"
                else:
                    message = (
                        f"{what} writes userdata key '{key}', not declared as an output key: "
                        "the original logged and dropped the write, strict mode raises "
                        "InvalidUserCodeError"
                    )
                    suggestion = f"add '{key}' to output_keys (or io_keys)"
                self.add(node, CHANGE, "userdata", message, suggestion)
            elif not store and inputs is not None and key not in inputs:
                self.add(
                    node,
                    CHANGE,
                    "userdata",
                    f"{what} reads userdata key '{key}', not declared as an input key (the "
                    "original raised too, except in a state contained in an Iterator)",
                    f"add '{key}' to input_keys (or io_keys)",
                )


def _keyword(call: ast.Call, name: str) -> ast.expr | None:
    for keyword in call.keywords:
        if keyword.arg == name:
            return keyword.value
    return None


def _union(a: _Interface, b: _Interface) -> _Interface:
    def join(x: set[str] | None, y: set[str] | None) -> set[str] | None:
        return None if x is None or y is None else x | y

    return _Interface(join(a.inputs, b.inputs), join(a.outputs, b.outputs))


def _calls_outside_nested_withs(body: list[ast.stmt], machines: set[str]) -> Iterable[ast.Call]:
    """Calls in ``body``, not descending into ``with other_machine:`` blocks."""
    stack: list[ast.AST] = list(body)
    while stack:
        node = stack.pop()
        if isinstance(node, ast.With) and any(
            isinstance(item.context_expr, ast.Name) and item.context_expr.id in machines
            for item in node.items
        ):
            continue
        if isinstance(node, ast.Call):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _looks_ros1(name: str, first: ast.expr) -> bool:
    """The first positional argument is what the ROS 1 signature puts there."""
    if isinstance(first, ast.Constant) and isinstance(first.value, str):
        return True  # action/service/topic/server name
    if name == "ConditionState" and isinstance(first, ast.Name | ast.Lambda):
        return isinstance(first, ast.Lambda) or not first.id.endswith("node")
    return False


def _userdata_access(node: ast.AST, ud: str) -> tuple[str | None, bool, bool]:
    """(key, is_store, through_attribute) for ``ud.key`` / ``ud['key']`` / ``ud.key.x = ...``."""
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == ud:
        if node.attr.startswith("_") or node.attr in {"keys", "update", "get"}:
            return None, False, False
        return node.attr, isinstance(node.ctx, ast.Store), False
    if (
        isinstance(node, ast.Subscript)
        and isinstance(node.value, ast.Name)
        and node.value.id == ud
        and isinstance(node.slice, ast.Constant)
        and isinstance(node.slice.value, str)
    ):
        return node.slice.value, isinstance(node.ctx, ast.Store), False
    if isinstance(node, ast.Attribute | ast.Subscript) and isinstance(node.ctx, ast.Store):
        inner = node.value
        if (
            isinstance(inner, ast.Attribute)
            and isinstance(inner.value, ast.Name)
            and inner.value.id == ud
        ):
            return inner.attr, True, True
    return None, False, False


_ROS1_LINE = re.compile(r"\b(rospy|roslib|actionlib|rostest)\b")


def check_source(text: str, filename: str = "<source>") -> list[Finding]:
    """Every finding for the program ``text`` (never runs or imports it)."""
    try:
        tree = ast.parse(text, filename)
    except SyntaxError as exc:
        findings = [
            Finding(
                filename,
                exc.lineno or 1,
                exc.offset or 1,
                CHANGE,
                "syntax",
                f"not valid Python 3 ({exc.msg}); Python 2 code (print statements, "
                "'except X, e') must be converted first, the rest of this list is a line scan",
                "convert with a Python 2 -> 3 tool, then run the check again",
            )
        ]
        for number, line in enumerate(text.splitlines(), 1):
            match = _ROS1_LINE.search(line)
            if match:
                findings.append(
                    Finding(
                        filename,
                        number,
                        match.start() + 1,
                        CHANGE,
                        "rospy" if match.group(1) != "actionlib" else "actionlib",
                        f"ROS 1 API ({match.group(1)})",
                        "see the rclpy equivalents in docs/porting-from-smach.md",
                    )
                )
        return findings
    checker = _Checker(filename)
    checker.visit(tree)
    checker.finish()
    return checker.findings


def check_file(path: str | Path) -> list[Finding]:
    """:func:`check_source` of a file (``OSError``/``UnicodeDecodeError`` propagate)."""
    path = Path(path)
    return check_source(path.read_text(encoding="utf-8"), str(path))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m smach.port_check",
        description="List what in SMACH programs changes or behaves differently with this "
        "package (static: the programs are not run).",
    )
    parser.add_argument("files", nargs="+", metavar="FILE", help="Python files to check")
    parser.add_argument("--json", action="store_true", help="one JSON object per finding")
    args = parser.parse_args(argv)
    status = 0
    counts: dict[str, int] = {}
    total = 0
    for name in args.files:
        try:
            findings = check_file(name)
        except (OSError, UnicodeDecodeError) as exc:
            print(f"{name}: cannot read: {exc}", file=sys.stderr)
            status = 2
            continue
        for finding in findings:
            total += 1
            counts[finding.kind] = counts.get(finding.kind, 0) + 1
            print(json.dumps(asdict(finding)) if args.json else finding.format())
            if finding.kind == CHANGE and status == 0:
                status = 1
    if not args.json:
        summary = ", ".join(f"{counts[k]} {k}" for k in (CHANGE, DIFFERS, NOTE) if k in counts)
        print(
            f"{total} finding{'s' if total != 1 else ''} in {len(args.files)} file"
            f"{'s' if len(args.files) != 1 else ''}" + (f" ({summary})" if summary else "")
        )
    return status


if __name__ == "__main__":
    sys.exit(main())
