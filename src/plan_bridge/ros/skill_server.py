"""A simulated robot node: serves a domain's actions as ROS 2 actions and services.

Run it as a process (the executive runs elsewhere, on this host or another)::

    python -m plan_bridge.ros.skill_server domains/fetch_drink --problem p01 --seed 1 --fail-rate 0.1
    python -m plan_bridge.ros.skill_server DOMAIN.pddl PROBLEM.pddl --seed 1 --fail-rate 0.2

**A domain folder** with Python (``setup()``, see :mod:`plan_bridge.missions.mission`): the
robot builds the domain's :class:`~plan_bridge.missions.mission.MissionSetup` (its real
simulated world, ``world.py``, with its faults) and, for each goal, executes the
domain's own hand-written skill state machine for that action against that world,
here, in the robot process. Feedback counts the skill's states as they are entered;
the result carries the skill's outcome and observations. The world's clock is paced
in wall time (``--time-scale`` wall seconds per simulated second,
:mod:`plan_bridge.ros.pacing`); a cancel preempts the skill machine and stops the
motion in progress (which then has no effect).

**A pyrobosim world** (a world folder such as ``domains/robosim_fetch``, or a
``WORLD.yaml`` with ``--goal``; ``--events`` adds its changes at simulated times): the
robot loads the world (:class:`~plan_bridge.robosim.world.RobosimWorld`, pyrobosim's
seeded faults) and runs the robosim skill machines (:mod:`plan_bridge.robosim.skills`)
against it. The world paces itself: ``--time-scale`` is its
:attr:`~plan_bridge.robosim.world.RobosimWorld.time_scale` (drives run at pyrobosim's
real-time factor ``1 / S``, other actions wait ``S`` times their duration); a cancel
preempts the skill machine, which cancels pyrobosim's action (a drive stops where the
robot is). ``info`` adds the world's figures (distance driven, battery, changes).

**A bare domain.pddl, or a folder without Python:** every action is performed
symbolically in a :class:`~plan_bridge.execution.simulation.SimulatedWorld` after
``--action-time`` seconds of wall time (feedback every tenth of it, cancellable
throughout), failing with probability ``--fail-rate`` (seeded).

The wire format is in :mod:`plan_bridge.ros.protocol`. The process prints
``ready`` once serving and one line per goal event (``goal``, ``succeeded``,
``failed``, ``canceled``, followed by the action; ``state PATH`` for each state a
domain skill enters; ``world CHANGE`` for each change of a pyrobosim world's events),
which tests and humans can follow. SIGINT or SIGTERM end it.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import smach
from plan_bridge.belief import Observation, normalise_observations
from plan_bridge.errors import FactError
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import Fact, PlanningTask, parse_fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.ros.pacing import Pacer, Run
from plan_bridge.ros.protocol import (
    FACTS_SERVICE,
    HEARTBEAT_PERIOD,
    HEARTBEAT_TOPIC,
    INFO_SERVICE,
    MAX_PERFORM_HOLD,
    PERFORM_DONE,
    PERFORM_RUNNING,
    PERFORM_SERVICE,
    REPORT_SERVICE,
    SUBMIT_SERVICE,
    Performance,
    action_topic,
    encode_result,
    interfaces,
    task_digest,
)
from plan_bridge.ros.robot_node import run_robot_node
from plan_bridge.skills.registry import SkillError, SkillRegistry
from smach.introspection.events import Event, StateEntered
from smach.ros.executor import publisher_events
from smach.ros.rclpy_api import (
    ActionServer,
    CancelResponse,
    GoalResponse,
    ReentrantCallbackGroup,
    StringMsg,
)

if TYPE_CHECKING:
    from plan_bridge.robosim.world import RobosimWorld

__all__ = ["SkillServer", "main"]

#: The predicates a pyrobosim world reads from pyrobosim itself (``RobosimWorld.truth``);
#: the other facts of its ``facts`` service are the problem's (static) initial ones.
ROBOSIM_PREDICATES = ("at", "holding", "handempty", "isopen", "islocked", "has", "searched")


class SkillServer:
    """Serves ``world``'s task actions on ``node`` under ``prefix``.

    Without ``skills``, each action is performed symbolically by ``world.perform``
    after ``action_time`` seconds. With ``skills`` (a domain's registry acting on
    ``world``), each goal executes the skill's state machine in the goal's thread;
    ``pacer`` (see :func:`~plan_bridge.ros.pacing.pace`) lets a cancel stop the
    motion in progress. Goals run one at a time (one robot) unless ``concurrent``.

    ``world`` is a :class:`SimulatedWorld` (its ``task`` is served), or a pyrobosim
    :class:`~plan_bridge.robosim.world.RobosimWorld` with ``task`` (the generated
    problem) and the robosim ``skills``; it paces itself (its ``time_scale``).

    The caller spins ``node`` (a multi-threaded executor: goals block their thread).
    ``log`` receives one line per goal event. ``meta`` is added to :meth:`info`.
    """

    #: Tickets kept (oldest are forgotten beyond this).
    MAX_TICKETS = 1000

    def __init__(
        self,
        node: Any,
        world: SimulatedWorld | RobosimWorld,
        *,
        task: PlanningTask | None = None,
        prefix: str = "skills",
        action_time: float = 0.2,
        log: Callable[[str], None] | None = None,
        skills: SkillRegistry | None = None,
        pacer: Pacer | None = None,
        concurrent: bool = False,
        meta: Mapping[str, Any] | None = None,
        robot: str | None = None,
    ) -> None:
        fibonacci, basic_types, trigger = interfaces()
        self._fibonacci = fibonacci
        self.node = node
        self.world = world
        if isinstance(world, SimulatedWorld):
            self.task: PlanningTask = world.task if task is None else task
            self._model = world.model
        else:
            if task is None or skills is None:
                raise ValueError("a pyrobosim world is served with its task and its skills")
            self.task = task
            self._model = ActionModel(task)
        # The objects a step may name: the task's; of a pyrobosim world, every object
        # of its map (the executive plans tasks of the places each plan needs).
        self._objects = set(self.task.objects)
        if not isinstance(world, SimulatedWorld):
            self._objects |= {name.lower() for name in world.model.names}
        self.prefix = prefix.rstrip("/")
        self.action_time = action_time
        self.skills = skills
        self.pacer = pacer
        self.concurrent = concurrent
        self.meta = dict(meta or {})
        #: The one robot this node is (its skills act through the world node's body,
        #: its ``world`` is only a copy for names): None for a node with the world.
        self.robot = robot
        self._log = log or (lambda line: None)
        self._group = ReentrantCallbackGroup()
        # One robot: actions run one at a time (unless the domain runs several robots).
        self._robot = threading.Lock()
        self._lock = threading.Lock()
        self._tickets: dict[int, PlanStep] = {}
        self._reports: dict[int, str] = {}
        self._next_ticket = 1
        # perform requests by request id (a repeated request joins the first one).
        self._performances: dict[int, Performance] = {}
        # Goals being executed: goal id -> (run, skill state once built, step).
        self._runs: dict[bytes, tuple[Run, smach.State | None, PlanStep]] = {}
        self._servers: list[Any] = []
        for name in sorted(self.task.actions):
            self._servers.append(
                ActionServer(
                    node,
                    fibonacci,
                    action_topic(self.prefix, name),
                    execute_callback=lambda handle, name=name: self._execute(name, handle),
                    goal_callback=lambda goal, name=name: self._on_goal(name, goal),
                    cancel_callback=self._on_cancel,
                    callback_group=self._group,
                )
            )
        self._services = [
            node.create_service(
                basic_types, f"{self.prefix}/{name}", callback, callback_group=self._group
            )
            for name, callback in (
                (SUBMIT_SERVICE, self._on_submit),
                (REPORT_SERVICE, self._on_report),
                (PERFORM_SERVICE, self._on_perform),
            )
        ]
        for name, callback in ((FACTS_SERVICE, self._on_facts), (INFO_SERVICE, self._on_info)):
            self._services.append(
                node.create_service(
                    trigger, f"{self.prefix}/{name}", callback, callback_group=self._group
                )
            )
        # The heartbeat (protocol.HEARTBEAT_TOPIC): beats while the node is spun.
        beat_topic = f"{self.prefix}/{HEARTBEAT_TOPIC}"
        self._beats = 0
        self._heartbeat = node.create_publisher(
            StringMsg, beat_topic, 1, event_callbacks=publisher_events(beat_topic)
        )
        self._beat_timer = node.create_timer(
            HEARTBEAT_PERIOD, self._beat, callback_group=self._group
        )

    @property
    def mode(self) -> str:
        if self.skills is None:
            return "symbolic"
        if self.robot is not None:
            return f"pyrobosim skills of {self.robot}"
        return "domain skills" if isinstance(self.world, SimulatedWorld) else "pyrobosim skills"

    def info(self) -> dict[str, Any]:
        """What the ``info`` service answers: who this robot is and how its world is."""
        with self._lock:
            busy = sorted(str(step) for _, _, step in self._runs.values())
        world = self.world
        faults = list(world.faults) if isinstance(world, SimulatedWorld) else []
        own = {
            **self.meta,
            "node": self.node.get_fully_qualified_name(),
            "prefix": self.prefix,
            "pid": os.getpid(),
            "mode": self.mode,
            "task": self.task.name,
            "digest": task_digest(self.task),
            "concurrent": self.concurrent,
            "busy": busy,
        }
        if self.robot is not None:  # the world and its numbers are the world node's
            return own
        return {
            **own,
            "sim_time": round(world.now(), 3),
            "actions_run": world.actions_run,
            "faults_injected": int(world.faults_injected),
            "faults": [f"{f.kind}: {f.detail}" for f in faults[-50:]],
            "goal_reached": bool(world.goal_reached()),
            # The world's own numbers (a pyrobosim world's distance, battery, changes):
            # what ``plan-bridge run --json`` shows of a world in its own process.
            "figures": world.figures(),
        }

    def facts(self) -> list[str]:
        """The facts true in the robot's world, as PDDL text (the ``facts`` service);
        ValueError on a node of one robot (the world node has them)."""
        if self.robot is not None:
            raise ValueError(f"{self.robot}'s node has no world: ask the world node's facts")
        world = self.world
        if isinstance(world, SimulatedWorld):
            return sorted(" ".join(f) for f in world.facts)
        return sorted(" ".join(f) for f in _robosim_facts(world, self.task))

    def _changes(self) -> int:
        """How many changes a pyrobosim world's events made so far (0 for others)."""
        return 0 if isinstance(self.world, SimulatedWorld) else len(self.world.changes)

    def _log_changes(self, since: int) -> None:
        if not isinstance(self.world, SimulatedWorld):
            for change in self.world.changes[since:]:
                self._log(f"world {change}")

    # -- parsing ------------------------------------------------------------------------------
    def step_of(self, text: str) -> PlanStep:
        """The plan step named by ``text``; ValueError naming what is wrong."""
        words = parse_fact(text)
        action, args = words[0], tuple(words[1:])
        schema = self.task.actions.get(action)
        if schema is None:
            raise ValueError(f"unknown action {action!r}; actions: {', '.join(self.task.actions)}")
        if len(args) != schema.arity:
            raise ValueError(f"{action} takes {schema.arity} arguments, got {len(args)}")
        unknown = [a for a in args if a not in self._objects]
        if unknown:
            raise ValueError(f"unknown objects {unknown}")
        if self.robot is not None and args[:1] != (self.robot,):
            raise ValueError(f"this is {self.robot}'s node: {text} is not its step")
        return PlanStep(action, args)

    def _ticket(self, ticket: int) -> PlanStep | None:
        with self._lock:
            return self._tickets.get(ticket)

    @contextlib.contextmanager
    def _the_robot(self) -> Iterator[None]:
        if self.concurrent:
            yield
        else:
            with self._robot:
                yield

    # -- services ---------------------------------------------------------------------------------
    def _on_submit(self, request: Any, response: Any) -> Any:
        try:
            step = self.step_of(request.string_value)
        except (ValueError, FactError) as exc:
            response.int64_value = 0
            response.string_value = str(exc)
            self._log(f"refused {request.string_value[:200]}: {exc}")
            return response
        with self._lock:
            ticket = self._next_ticket
            self._next_ticket += 1
            self._tickets[ticket] = step
            while len(self._tickets) > self.MAX_TICKETS:
                forgotten = next(iter(self._tickets))
                del self._tickets[forgotten]
                self._reports.pop(forgotten, None)
        response.int64_value = ticket
        return response

    def _on_report(self, request: Any, response: Any) -> Any:
        with self._lock:
            report = self._reports.get(request.int64_value)
        response.bool_value = report is not None
        response.string_value = report or encode_result(False, [], "no report for this ticket")
        return response

    def _on_perform(self, request: Any, response: Any) -> Any:
        ident = int(request.int64_value)
        if ident == 0:  # no request id: perform now and answer when done (not repeatable)
            job = Performance(request.string_value)
            self._perform(job)
        else:
            job = self._performance(ident, request.string_value)
            hold = float(request.float64_value)
            job.done.wait(min(hold, MAX_PERFORM_HOLD) if hold > 0 else None)
        done = job.done.is_set()
        response.int64_value = PERFORM_DONE if done else PERFORM_RUNNING
        response.bool_value = job.ok
        response.string_value = job.result
        return response

    def _performance(self, ident: int, text: str) -> Performance:
        """The performance of request ``ident``: started now unless it is a repeat."""
        with self._lock:
            job = self._performances.get(ident)
            if job is None:
                job = self._performances[ident] = Performance(text)
                finished = [k for k, j in self._performances.items() if j.done.is_set()]
                for forgotten in finished[: max(0, len(self._performances) - self.MAX_TICKETS)]:
                    del self._performances[forgotten]
                threading.Thread(
                    target=self._perform, args=(job,), name=f"perform-{ident}", daemon=True
                ).start()
            elif job.text != text:
                refused = Performance(text)
                refused.refuse(f"request id {ident} was already used for {job.text!r}")
                return refused
        return job

    def _perform(self, job: Performance) -> None:
        try:
            step = self.step_of(job.text)
        except (ValueError, FactError) as exc:
            job.refuse(str(exc))
            return
        self._log(f"goal {step}")
        if self.skills is not None:
            outcome, text = self._run_skill(step, Run(), None)
            ok = outcome == "succeeded"
        else:
            with self._the_robot():
                time.sleep(self.action_time)
                ok, observations = self._perform_symbolically(step)
            text = encode_result(ok, observations)
        self._log(f"{'succeeded' if ok else 'failed'} {step}")
        job.finish(ok, text)

    def _perform_symbolically(self, step: PlanStep) -> tuple[bool, list[Observation]]:
        world = self.world
        assert isinstance(world, SimulatedWorld)  # a pyrobosim world always has its skills
        return world.perform(step)

    def _on_facts(self, request: Any, response: Any) -> Any:
        try:
            response.message = json.dumps(self.facts())
            response.success = True
        except ValueError as exc:
            response.success, response.message = False, str(exc)
        return response

    def _on_info(self, request: Any, response: Any) -> Any:
        response.success = True
        response.message = json.dumps(self.info())
        return response

    # -- action servers ------------------------------------------------------------------------------
    def _on_goal(self, action: str, goal: Any) -> Any:
        step = self._ticket(goal.order)
        if step is None or step.action != action:
            self._log(f"rejected ticket {goal.order} on {action}")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_cancel(self, handle: Any) -> Any:
        with self._lock:
            entry = self._runs.get(bytes(handle.goal_id.uuid))
        if entry is not None:
            run, state, _ = entry
            run.halt()
            if state is not None:
                state.request_preempt()
        return CancelResponse.ACCEPT

    def _execute(self, action: str, handle: Any) -> Any:
        ticket = handle.request.order
        step = self._ticket(ticket)
        result = self._fibonacci.Result(sequence=[ticket])
        if step is None:
            handle.abort()
            return result
        self._log(f"goal {step}")
        if self.skills is not None:
            return self._execute_skill(step, ticket, handle, result)
        with self._the_robot():
            for tick in range(10):
                if handle.is_cancel_requested:
                    with self._lock:
                        self._reports[ticket] = encode_result(False, [], "cancelled")
                    handle.canceled()
                    self._log(f"canceled {step}")
                    return result
                handle.publish_feedback(self._fibonacci.Feedback(sequence=[tick * 10]))
                time.sleep(self.action_time / 10)
            ok, observations = self._perform_symbolically(step)
        report = encode_result(
            ok, observations, "" if ok else "the action failed in the simulated world"
        )
        self._end_goal(handle, step, ticket, report, "succeeded" if ok else "aborted")
        return result

    # -- domain skills ----------------------------------------------------------------------------
    def _execute_skill(self, step: PlanStep, ticket: int, handle: Any, result: Any) -> Any:
        run = Run()
        key = bytes(handle.goal_id.uuid)
        with self._lock:
            self._runs[key] = (run, None, step)
        if handle.is_cancel_requested:
            run.halt()
        entered = [0]

        def progress(path: str) -> None:
            entered[0] += 1
            handle.publish_feedback(self._fibonacci.Feedback(sequence=[entered[0]]))

        try:
            outcome, text = self._run_skill(step, run, key, progress)
        finally:
            with self._lock:
                self._runs.pop(key, None)
        self._end_goal(handle, step, ticket, text, outcome)
        return result

    def _end_goal(
        self, handle: Any, step: PlanStep, ticket: int, report: str, outcome: str
    ) -> None:
        """Keep the ``report`` for ``ticket`` and end the goal by ``outcome``: succeeded,
        canceled (preempted after a cancel request), else aborted."""
        with self._lock:
            self._reports[ticket] = report
        if outcome == "succeeded":
            handle.succeed()
            self._log(f"succeeded {step}")
        elif outcome == "preempted" and handle.is_cancel_requested:
            handle.canceled()
            self._log(f"canceled {step}")
        else:
            handle.abort()
            self._log(f"failed {step}")

    def _run_skill(
        self,
        step: PlanStep,
        run: Run,
        key: bytes | None,
        progress: Callable[[str], None] | None = None,
    ) -> tuple[str, str]:
        """Execute the domain's skill for ``step``: (outcome, JSON result payload)."""
        assert self.skills is not None
        with self._the_robot():
            if run.halted:
                return "preempted", encode_result(False, [], "cancelled before it started")
            try:
                state, skill = self.skills.create(step)
            except SkillError as exc:
                return "aborted", encode_result(False, [], str(exc))
            if key is not None:
                with self._lock:
                    self._runs[key] = (run, state, step)
            if run.halted:
                state.request_preempt()
            label = f"/{step.action}"
            changes = self._changes()

            def on_event(event: Event) -> None:
                if isinstance(event, StateEntered):
                    path = label + event.path.removeprefix("/ROOT")
                    self._log(f"  state {path}")
                    if progress is not None:
                        progress(path)

            container = state if isinstance(state, smach.Container) else None
            if container is not None:
                container.add_listener(on_event)
            ud = smach.UserData()
            ud.action = step.action
            ud.arguments = step.arguments
            ud.params = self._model.ground(step).binding
            detail = ""
            try:
                with self.pacer.running(run) if self.pacer else contextlib.nullcontext(run):
                    outcome = state.execute(ud)
            except Exception as exc:
                outcome = "preempted" if run.halted else "aborted"
                detail = "halted" if run.halted else f"the skill raised: {exc}"
            finally:
                if container is not None:
                    container.remove_listener(on_event)
                self._log_changes(changes)
        mapped = skill.map_outcome(str(outcome)) if skill is not None else str(outcome)
        if mapped == "preempted" or (run.halted and mapped != "succeeded"):
            return "preempted", encode_result(False, [], detail or "cancelled")
        try:
            observations = normalise_observations(ud._data.get("observations"))
        except ValueError as exc:
            return "aborted", encode_result(False, [], f"malformed observations: {exc}")
        ok = mapped == "succeeded"
        if not ok and not detail:
            detail = f"the skill ended {outcome}"
        return ("succeeded" if ok else "aborted"), encode_result(ok, observations, detail)

    def halt_all(self) -> None:
        """Stop every running skill (the robot is shutting down)."""
        with self._lock:
            entries = list(self._runs.values())
        for run, state, _ in entries:
            run.halt()
            if state is not None:
                state.request_preempt()

    def _beat(self) -> None:
        self._beats += 1
        self._heartbeat.publish(StringMsg(data=str(self._beats)))

    def destroy(self) -> None:
        self.halt_all()
        self.node.destroy_timer(self._beat_timer)
        self.node.destroy_publisher(self._heartbeat)
        for server in self._servers:
            server.destroy()
        for service in self._services:
            self.node.destroy_service(service)


def _robosim_facts(world: RobosimWorld, task: PlanningTask) -> set[Fact]:
    """The facts true in a pyrobosim world now: the atoms of :data:`ROBOSIM_PREDICATES`
    over the task's objects as pyrobosim has them, and the other initial facts."""
    by_type: dict[str, list[str]] = {}
    for name, kind in task.objects.items():
        by_type.setdefault(kind, []).append(name)
    bots, items, spots = by_type.get("bot", []), by_type.get("item", []), by_type.get("spot", [])
    gates = [*by_type.get("hall", []), *by_type.get("fixture", [])]
    candidates: list[Fact] = [
        *(("at", r, s) for r in bots for s in spots),
        *(("at", i, s) for i in items for s in spots),
        *(("holding", r, i) for r in bots for i in items),
        *(("handempty", r) for r in bots),
        *((p, g) for p in ("isopen", "islocked") for g in gates),
        *(("has", g, i) for g in by_type.get("fixture", []) for i in items),
        *(("searched", s) for s in spots),
    ]
    facts = {f for f in task.initial_facts if f[0] not in ROBOSIM_PREDICATES}
    facts.update(f for f in candidates if world.truth(f))
    return facts


def main(argv: Sequence[str] | None = None) -> int:
    """The robot node's command line: :mod:`plan_bridge.ros.robot_node` serving with a
    :class:`SkillServer`."""
    return run_robot_node(argv, SkillServer)


if __name__ == "__main__":
    sys.exit(main())
