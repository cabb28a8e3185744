"""The executive's side of a mission across processes (``plan-bridge run --ros``).

A :class:`RobotConnection` joins the ROS graph with its own rclpy context and node,
starts a robot node (``python -m plan_bridge.ros.skill_server``) as a subprocess or
connects to one that is already running, checks that the robot runs the same
problem (``info``: :func:`~plan_bridge.ros.protocol.task_digest`), and builds the
executive's skills as ROS clients of it (:func:`~plan_bridge.ros.ros_skills`). For a
pyrobosim world it does the same for the world node and a node per robot.
:meth:`close` leaves the graph and stops the processes it started.
"""

from __future__ import annotations

import collections
import itertools
import os
import shlex
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TextIO

import smach
from plan_bridge.errors import PlanBridgeError
from plan_bridge.planning.types import PlanStep
from plan_bridge.ros.protocol import HEARTBEAT_TIMEOUT, HEARTBEAT_TOPIC, task_digest
from plan_bridge.ros.robot_world import RobotWorld
from plan_bridge.ros.skills import remote_info, ros_skills
from plan_bridge.skills.registry import SkillRegistry

if TYPE_CHECKING:
    from plan_bridge.orders.requests import OrderDesk
    from plan_bridge.pddl.knowledge import KnowledgeBase
    from plan_bridge.ros.knowledge_services import KnowledgeServices
    from plan_bridge.ros.order_services import OrderServices

__all__ = ["RobotConnection", "RobotError", "RobotLost"]

_nodes = itertools.count(1)


class RobotError(PlanBridgeError):
    """The robot node could not be started or reached, or runs another problem."""


class RobotLost(smach.State):
    """The skill of a step while the robot node is gone: ``aborted`` at once."""

    def __init__(self, step: PlanStep, reason: str) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])
        self.step = step
        self.reason = reason

    def execute(self, ud: smach.UserData) -> str:
        smach.logerr(f"skill {self.step}: {self.reason}")
        return "aborted"


class RobotConnection:
    """A rclpy node of the executive and the robot node it drives.

    ``start_robot``: start ``python -m plan_bridge.ros.skill_server`` for
    ``target`` (a :class:`~plan_bridge.missions.mission.Target`) with ``seed``,
    ``fail_rate`` and ``time_scale``, and stop it in :meth:`close`. For a pyrobosim
    world target the robot gets its goal (``--goal``, and ``--problem`` when it is a
    goal of goals.yaml) and ``events`` (an events file: the world's changes happen in
    the robot's process). Otherwise
    connect to the robot node already serving under ``prefix``. ``log`` receives
    what happens, and with ``echo_robot`` the robot's own lines, prefixed
    ``[robot]`` (the goals and the states of its skills).

    ``robot_nodes`` (a pyrobosim world): the node under ``prefix`` is the *world node*,
    and each robot of the world has a node of its own under ``PREFIX/ROBOT``
    (:attr:`members`, started side by side or found), running its skill machines
    through the world node's bodies (:mod:`plan_bridge.ros.body_link`). Each step goes
    to its robot's node; :meth:`robots_gone` says whose node is gone. Lines are
    prefixed ``[world]`` and ``[ROBOT]``.
    """

    #: Seconds to wait for a robot we started to print ``ready``.
    START_TIMEOUT = 60.0
    #: Lines of the robot's output kept (for error messages and tests).
    KEEP_LINES = 2000

    def __init__(
        self,
        target: Any,
        *,
        prefix: str | None = None,
        start_robot: bool = True,
        seed: int = 0,
        fail_rate: float | None = None,
        time_scale: float = 0.01,
        events: str | os.PathLike[str] | None = None,
        wait_timeout: float = 20.0,
        server_wait_timeout: float = 10.0,
        log: TextIO | None = None,
        echo_robot: bool = True,
        robot_nodes: bool = False,
    ) -> None:
        self.target = target
        self.robot_nodes = robot_nodes
        self.echo_robot = echo_robot
        self.start_robot = start_robot
        self.prefix = prefix or (f"robot_{os.getpid()}" if start_robot else "robot")
        self.seed = seed
        self.fail_rate = fail_rate
        self.time_scale = time_scale
        self.events = None if events is None else os.fspath(events)
        self.wait_timeout = wait_timeout
        self.server_wait_timeout = server_wait_timeout
        self.log = log
        self.process: subprocess.Popen[str] | None = None
        self.lines: collections.deque[str] = collections.deque(maxlen=self.KEEP_LINES)
        self.robot_info: dict[str, Any] = {}
        self.context: Any = None
        self.node: Any = None
        self._ready = threading.Event()
        self._pump_thread: threading.Thread | None = None
        self._knowledge_services: list[KnowledgeServices] = []
        self._order_services: list[OrderServices] = []
        #: When the robot's heartbeat was last heard (None: not yet).
        self._last_beat: float | None = None
        #: With ``robot_nodes``: each robot's own node (process), by robot name.
        self.members: dict[str, RobotConnection] = {}
        #: The world's connection, for the node of one of its robots (``robot_name``).
        self._parent: RobotConnection | None = None
        self.robot_name: str | None = None
        self._command: list[str] = []

    # -- life cycle -------------------------------------------------------------------
    def open(self) -> RobotConnection:
        """Start or find the robot and connect; RobotError if that fails."""
        try:
            self._open()
        except BaseException:
            self.close()
            raise
        return self

    def _open(self) -> None:
        if self.start_robot and not os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE"):
            # Both processes run here: keep DDS traffic on this machine.
            os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        where = (
            f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID', '0 (default)')}, "
            f"discovery {os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE', 'SUBNET (default)')}"
        )
        if self.start_robot:
            self._say(f"ros: starting a {self._kind} under /{self.prefix} ({where})")
            self._start_process()
            self._wait_ready()
        else:
            self._say(f"ros: connecting to the running {self._kind} under /{self.prefix} ({where})")
        self._join_graph()
        self._check_info()
        if self.robot_nodes and self.robot_info.get("robots") and self._parent is None:
            self._open_members(list(self.robot_info["robots"]))

    @property
    def _kind(self) -> str:
        if self._parent is not None:
            return f"robot node of {self.robot_name}"
        return "world node" if self.robot_nodes else "robot node"

    def _join_graph(self) -> None:
        from smach.ros.rclpy_api import rclpy

        if self._parent is not None:  # a robot of the world: the world's node listens
            self.node = self._parent.node
        else:
            self.context = rclpy.Context()
            rclpy.init(context=self.context)
            self.node = rclpy.create_node(
                f"plan_bridge_executive_{os.getpid()}_{next(_nodes)}", context=self.context
            )
        self._listen_to_heartbeat()

    def _check_info(self) -> None:
        """Read the node's ``info``: it answers, and runs the executive's problem."""
        try:
            self.robot_info = remote_info(self.node, prefix=self.prefix, timeout=self.wait_timeout)
        except RuntimeError as exc:
            hint = (
                ""
                if self.start_robot
                else " (start one with: python -m plan_bridge.ros.skill_server "
                f"{shlex.join(self._target_arguments())} "
                f"--prefix {self._world_prefix}"
                + (f" --robot {self.robot_name}" if self.robot_name else "")
                + "; same ROS_DOMAIN_ID on both sides)"
            )
            raise RobotError(f"no {self._kind} answers under /{self.prefix}: {exc}{hint}") from None
        info = self.robot_info
        if info.get("digest") != task_digest(self.target.task):
            raise RobotError(
                f"the {self._kind} under /{self.prefix} runs {info.get('target')} "
                f"{info.get('problem')} ({info.get('task')}), not {self.target.name} "
                f"{self.target.problem_path.name}: start it with the same domain and problem"
            )
        if info.get("actions_run") or info.get("busy"):
            self._say(
                f"ros: warning: the {self._kind} has already run {info.get('actions_run')} actions "
                f"(busy: {', '.join(info.get('busy') or []) or 'no'}); its world is no longer the "
                f"problem's initial state, which the plan assumes: restart it for a new mission"
            )
        how = f"started here, pid {info.get('pid')}" if self.start_robot else "already running"
        goal = f" goal {info['goal']}" if info.get("goal") else ""
        self._say(
            f"ros: {self._kind} {info.get('node')} ({how}) serves {info.get('target')} "
            f"{info.get('problem')}{goal} under /{self.prefix}: {info.get('mode')}, seed "
            f"{info.get('seed')}, fail rate {info.get('fail_rate')}"
            + (f", time scale {info['time_scale']}" if info.get("time_scale") is not None else "")
        )

    def _open_members(self, robots: Sequence[str]) -> None:
        """A node of each robot of the world, under ``PREFIX/ROBOT``: started side by side
        (each loads the world), then checked one by one."""
        for name in robots:
            member = RobotConnection(
                self.target,
                prefix=f"{self.prefix}/{name}",
                start_robot=self.start_robot,
                seed=self.seed,
                fail_rate=self.fail_rate,
                time_scale=self.time_scale,
                wait_timeout=self.wait_timeout,
                server_wait_timeout=self.server_wait_timeout,
                log=self.log,
                echo_robot=self.echo_robot,
            )
            member._parent = self
            member.robot_name = name
            self.members[name] = member
            if self.start_robot:
                member._start_process()
        for member in self.members.values():
            if self.start_robot:
                member._wait_ready()
            member._join_graph()
            member._check_info()

    @property
    def _world_prefix(self) -> str:
        return self._parent.prefix if self._parent is not None else self.prefix

    def _listen_to_heartbeat(self) -> None:
        """Hear the robot's heartbeat (protocol.HEARTBEAT_TOPIC) on smach's helper node,
        which is spun whether or not anybody spins ``self.node``."""
        from smach.ros.executor import SmachExecutor, subscription_events
        from smach.ros.rclpy_api import StringMsg

        helper = SmachExecutor.for_node(self.node)
        topic = f"/{self.prefix}/{HEARTBEAT_TOPIC}"
        helper.node.create_subscription(
            StringMsg,
            topic,
            self._on_beat,
            1,
            callback_group=helper.callback_group,
            event_callbacks=subscription_events(topic),
        )

    def _on_beat(self, message: Any) -> None:
        self._last_beat = time.monotonic()

    def _target_path(self) -> str:
        folder = getattr(self.target, "folder", None)
        if folder is None:
            # A pyrobosim world file (its target has no folder), or a bare domain.pddl.
            folder = getattr(self.target, "world_file", None) or self.target.domain_path
        return str(folder)

    def _target_arguments(self) -> list[str]:
        """The robot node's target arguments: the same problem (or world and goal)."""
        arguments = [self._target_path()]
        goal = getattr(self.target, "goal_text", None)
        if goal is None:  # a PDDL target: its problem file (and the goal given at run time)
            given = self.target.given_goal
            return [
                *arguments,
                "--problem",
                str(self.target.problem_path),
                *(["--goal", given] if given is not None else []),
            ]
        name = getattr(self.target, "goal_name", "")
        if name:  # a goal of goals.yaml: its name (shown by the robot) and its text
            arguments += ["--problem", name]
        arguments += ["--goal", goal]
        if self.events is not None:
            arguments += ["--events", self.events]
        return arguments

    def _start_process(self) -> None:
        command = [
            sys.executable,
            "-m",
            "plan_bridge.ros.skill_server",
            *self._target_arguments(),
            "--seed",
            str(self.seed),
            "--prefix",
            self._world_prefix,
            "--node-name",
            f"robot_{os.getpid()}" + (f"_{self.robot_name}" if self.robot_name else ""),
            "--time-scale",
            str(self.time_scale),
            "--exit-with-parent",
        ]
        if self.robot_name is not None:
            command += ["--robot", self.robot_name]
        if self.fail_rate is not None:
            command += ["--fail-rate", str(self.fail_rate)]
        self._command = command
        # stderr is inherited: the robot's errors appear as they happen.
        self.process = subprocess.Popen(
            command, stdout=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL
        )
        self._pump_thread = threading.Thread(target=self._pump, name="robot-output", daemon=True)
        self._pump_thread.start()

    def _wait_ready(self) -> None:
        process = self.process
        assert process is not None
        deadline = time.monotonic() + self.START_TIMEOUT
        while not self._ready.wait(0.05):
            if process.poll() is not None:
                raise RobotError(
                    f"the {self._kind} exited with code {process.returncode} before it was "
                    f"ready: {' '.join(self._command[1:])}"
                )
            if time.monotonic() > deadline:
                raise RobotError(f"the {self._kind} was not ready within {self.START_TIMEOUT:g} s")

    def _pump(self) -> None:
        process = self.process
        assert process is not None and process.stdout is not None
        for raw in process.stdout:
            line = raw.rstrip("\n")
            self.lines.append(line)
            if line == "ready":
                self._ready.set()
            elif self.echo_robot:
                self._say(f"  [{self._label}] {line}")
        code = process.wait()
        if self.node is not None:  # not stopped by close()
            self._say(f"ros: the {self._kind} exited (code {code})")

    @property
    def _label(self) -> str:
        if self.robot_name is not None:
            return self.robot_name
        return "world" if self.robot_nodes else "robot"

    def _say(self, line: str) -> None:
        if self.log is not None:
            print(line, file=self.log, flush=True)

    # -- use ----------------------------------------------------------------------------
    @property
    def concurrent(self) -> bool:
        return bool(self.robot_info.get("concurrent", False))

    def lost(self) -> str | None:
        """Why the robot node is gone (None while it is there).

        A robot started here is gone when its process exited; any robot when its
        heartbeat, once heard, stopped for ``HEARTBEAT_TIMEOUT`` (3 s: the project's
        own check, whatever the middleware), or when its ``info`` service left the ROS
        graph (a crashed process leaves it when its DDS lease expires: 2 s for
        ``skill_server``'s default ``--lease``). A robot's own node is gone with its
        world node too.
        """
        world_gone = self._parent.lost() if self._parent is not None else None
        return world_gone or self._own_loss()

    def _own_loss(self) -> str | None:
        """Why this node is gone, its world node aside (None while it is there)."""
        if self.process is not None and self.process.poll() is not None:
            return f"the {self._kind} exited (code {self.process.returncode})"
        if self.node is None:
            return "not connected"
        last = self._last_beat
        if last is not None and time.monotonic() - last > HEARTBEAT_TIMEOUT:
            return (
                f"the {self._kind} under /{self.prefix} sent no heartbeat for "
                f"{time.monotonic() - last:.1f} s"
            )
        wanted = f"/{self.prefix}/info"
        if not any(name == wanted for name, _ in self.node.get_service_names_and_types()):
            return f"the {self._kind} under /{self.prefix} left the ROS graph"
        return None

    def skills(self) -> SkillRegistry:
        """The executive's skills: ROS clients of the robot's actions.

        While the robot node is gone (:meth:`lost`), a step aborts at once instead
        of waiting ``server_wait_timeout`` for it (a running step within two liveness
        checks, 0.5 s apart), so the executive's recovery
        (retry, replan) ends quickly, ``aborted``; a robot that comes back is used
        again.
        """
        registry = ros_skills(
            self.node,
            self.target.task,
            prefix=self.prefix,
            server_wait_timeout=self.server_wait_timeout,
            # A running step aborts as soon as the robot is gone by our own checks.
            peer_alive=lambda: self.lost() is None,
        )
        remote = registry.fallback
        assert remote is not None
        # With a node per robot, a step runs on the node of its robot (its first argument).
        members = {name: member.skills().fallback for name, member in self.members.items()}

        def skill(step: PlanStep) -> smach.State:
            reason = self.lost()
            if reason is not None:
                return RobotLost(step, reason)
            own = members.get(step.arguments[0]) if step.arguments else None
            return own(step) if own is not None else remote(step)

        registry.fallback = skill
        return registry

    def describe(self) -> str:
        """Where the skills run, for the run's first line."""
        if self.members:
            return (
                f"pyrobosim skills on the robot nodes /{self.prefix}/ROBOT "
                f"({', '.join(self.members)}), the world on /{self.prefix}"
            )
        return f"{self.robot_info.get('mode')} on the robot node /{self.prefix}"

    def robots_gone(self) -> set[str]:
        """The robots whose own node is gone (:meth:`lost`): none without ``robot_nodes``,
        all of them when the world node is gone."""
        if self.members and self.lost() is not None:
            return set(self.members)
        return {name for name, member in self.members.items() if member._own_loss() is not None}

    def world(self) -> RobotWorld:
        """The robot's world as the executive sees it (a :class:`World`)."""
        return RobotWorld(self)

    def info(self, timeout: float = 5.0) -> dict[str, Any] | None:
        """The robot's current ``info`` (None if it does not answer)."""
        try:
            return remote_info(self.node, prefix=self.prefix, timeout=timeout)
        except RuntimeError:
            return None

    def serve_knowledge(
        self, knowledge: KnowledgeBase, *, name: str = "knowledge"
    ) -> KnowledgeServices:
        """Serve ``knowledge`` on the executive's node, PlanSys2-style
        (:mod:`plan_bridge.ros.knowledge_services`: ``/NAME/add_problem_goal``, ...);
        the services go in :meth:`close`."""
        from plan_bridge.ros.knowledge_services import KnowledgeServices

        if self.node is None:
            raise RobotError("not connected: open() the connection before serving a knowledge base")
        services = KnowledgeServices(self.node, knowledge, name=name)
        self._knowledge_services.append(services)
        return services

    def serve_orders(self, desk: OrderDesk, *, name: str = "orders") -> OrderServices:
        """Serve a mission's orders on the executive's node
        (:mod:`plan_bridge.ros.order_services`: ``/NAME/submit``, ``cancel``, ``list``
        and the ``status`` topic); the services go in :meth:`close`."""
        from plan_bridge.ros.order_services import OrderServices

        if self.node is None:
            raise RobotError("not connected: open() the connection before serving orders")
        services = OrderServices(self.node, desk, name=name)
        self._order_services.append(services)
        self._say(
            f"ros: orders served: {services.names['submit']}, {services.names['cancel']}, "
            f"{services.names['list']}; status on {services.names['status']}"
        )
        return services

    def close(self) -> None:
        """Leave the ROS graph; stop the robot processes we started."""
        for member in self.members.values():
            member.close()
        if self._parent is not None:
            self.node = None  # the world's node: it goes with the world's connection
        for services in self._knowledge_services:
            services.close()
        self._knowledge_services = []
        for order_services in self._order_services:
            order_services.close()
        self._order_services = []
        if self.context is not None:
            from smach.ros.executor import SmachExecutor

            helper = SmachExecutor._instances.get(id(self.context))
            if helper is not None:
                helper.shutdown()
            if self.node is not None:
                self.node.destroy_node()
            from smach.ros.rclpy_api import rclpy

            rclpy.try_shutdown(context=self.context)
            self.context = None
            self.node = None
        process = self.process
        if process is not None and process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(5)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)
        if self._pump_thread is not None:
            self._pump_thread.join(2)
        if process is not None and process.stdout is not None:
            process.stdout.close()

    def __enter__(self) -> RobotConnection:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()
