"""A simulated robot: serves every action of a PDDL domain as a ROS 2 action.

Run it as a process (the executive runs elsewhere, on this host or another)::

    python -m plan_bridge.ros.skill_server DOMAIN.pddl PROBLEM.pddl --seed 1 --fail-rate 0.2

Each action takes ``--action-time`` seconds of wall time (feedback every tenth of
it, cancellable throughout), then is performed in a
:class:`~plan_bridge.simulation.SimulatedWorld`, which fails it with probability
``--fail-rate`` (seeded). The wire format is in :mod:`plan_bridge.ros.protocol`.
The process prints ``ready`` once serving and one line per goal event
(``goal``, ``succeeded``, ``failed``, ``canceled``, followed by the action), which
tests and humans can follow. SIGINT or SIGTERM end it.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from plan_bridge.domain import PlanningTask, load_task, parse_fact
from plan_bridge.errors import FactError
from plan_bridge.planning import PlanStep
from plan_bridge.ros.protocol import (
    FACTS_SERVICE,
    PERFORM_SERVICE,
    REPORT_SERVICE,
    SUBMIT_SERVICE,
    action_topic,
    encode_result,
    interfaces,
)
from plan_bridge.simulation import SimulatedWorld
from smach.ros._api import (
    ActionServer,
    CancelResponse,
    ExternalShutdownException,
    GoalResponse,
    MultiThreadedExecutor,
    ReentrantCallbackGroup,
    rclpy,
)

__all__ = ["SkillServer", "main"]


class SkillServer:
    """Serves ``world``'s task actions on ``node`` under ``prefix``.

    The caller spins ``node`` (a multi-threaded executor: goals block their thread
    for ``action_time``). ``log`` receives one line per goal event.
    """

    #: Tickets kept (oldest are forgotten beyond this).
    MAX_TICKETS = 1000

    def __init__(
        self,
        node: Any,
        world: SimulatedWorld,
        *,
        prefix: str = "skills",
        action_time: float = 0.2,
        log: Callable[[str], None] | None = None,
    ) -> None:
        fibonacci, basic_types, trigger = interfaces()
        self._fibonacci = fibonacci
        self.node = node
        self.world = world
        self.task: PlanningTask = world.task
        self.prefix = prefix.rstrip("/")
        self.action_time = action_time
        self._log = log or (lambda line: None)
        self._group = ReentrantCallbackGroup()
        # One robot: actions run one at a time.
        self._robot = threading.Lock()
        self._lock = threading.Lock()
        self._tickets: dict[int, PlanStep] = {}
        self._reports: dict[int, str] = {}
        self._next_ticket = 1
        self._servers: list[Any] = []
        for name in sorted(self.task.actions):
            self._servers.append(
                ActionServer(
                    node,
                    fibonacci,
                    action_topic(self.prefix, name),
                    execute_callback=lambda handle, name=name: self._execute(name, handle),
                    goal_callback=lambda goal, name=name: self._on_goal(name, goal),
                    cancel_callback=lambda handle: CancelResponse.ACCEPT,
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
        self._services.append(
            node.create_service(
                trigger,
                f"{self.prefix}/{FACTS_SERVICE}",
                self._on_facts,
                callback_group=self._group,
            )
        )

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
        unknown = [a for a in args if a not in self.task.objects]
        if unknown:
            raise ValueError(f"unknown objects {unknown}")
        return PlanStep(action, args)

    def _ticket(self, ticket: int) -> PlanStep | None:
        with self._lock:
            return self._tickets.get(ticket)

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
        try:
            step = self.step_of(request.string_value)
        except (ValueError, FactError) as exc:
            response.bool_value = False
            response.string_value = encode_result(False, [], str(exc))
            return response
        self._log(f"goal {step}")
        with self._robot:
            time.sleep(self.action_time)
            ok, observations = self.world.perform(step)
        self._log(f"{'succeeded' if ok else 'failed'} {step}")
        response.bool_value = ok
        response.string_value = encode_result(ok, observations)
        return response

    def _on_facts(self, request: Any, response: Any) -> Any:
        response.success = True
        response.message = json.dumps(sorted(" ".join(f) for f in self.world.facts))
        return response

    # -- action servers ------------------------------------------------------------------------------
    def _on_goal(self, action: str, goal: Any) -> Any:
        step = self._ticket(goal.order)
        if step is None or step.action != action:
            self._log(f"rejected ticket {goal.order} on {action}")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _execute(self, action: str, handle: Any) -> Any:
        ticket = handle.request.order
        step = self._ticket(ticket)
        result = self._fibonacci.Result(sequence=[ticket])
        if step is None:
            handle.abort()
            return result
        self._log(f"goal {step}")
        with self._robot:
            for tick in range(10):
                if handle.is_cancel_requested:
                    with self._lock:
                        self._reports[ticket] = encode_result(False, [], "cancelled")
                    handle.canceled()
                    self._log(f"canceled {step}")
                    return result
                handle.publish_feedback(self._fibonacci.Feedback(sequence=[tick * 10]))
                time.sleep(self.action_time / 10)
            ok, observations = self.world.perform(step)
        with self._lock:
            self._reports[ticket] = encode_result(
                ok, observations, "" if ok else "the action failed in the simulated world"
            )
        if ok:
            handle.succeed()
            self._log(f"succeeded {step}")
        else:
            handle.abort()
            self._log(f"failed {step}")
        return result

    def destroy(self) -> None:
        for server in self._servers:
            server.destroy()
        for service in self._services:
            self.node.destroy_service(service)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m plan_bridge.ros.skill_server",
        description="Serve a PDDL domain's actions as ROS 2 actions, backed by a simulated world.",
    )
    parser.add_argument("domain")
    parser.add_argument("problem")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fail-rate", type=float, default=0.0)
    parser.add_argument("--action-time", type=float, default=0.2, help="seconds per action")
    parser.add_argument("--prefix", default="skills", help="action names: PREFIX/ACTION")
    parser.add_argument("--node-name", default="skill_server")
    args = parser.parse_args(argv)

    task = load_task(args.domain, args.problem)
    world = SimulatedWorld(task, seed=args.seed, fail_rate=args.fail_rate)
    rclpy.init()
    node = rclpy.create_node(args.node_name)

    def say(line: str) -> None:
        print(line, flush=True)

    server = SkillServer(node, world, prefix=args.prefix, action_time=args.action_time, log=say)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    say("ready")
    try:
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except ExternalShutdownException:
        pass
    say(f"faults {len(world.faults)}")
    server.destroy()
    executor.shutdown(timeout_sec=1)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
