"""Operator control of a running mission: skip a step, replan now, a new goal, abort.

:class:`MissionControl` is the plan-level half of runtime control (the state-level
half, pause/step/breakpoints/force, is :class:`smach.control.Controller`). A request
is stored and the plan machine in force is preempted; the :class:`Executive` takes
the request where its loop would otherwise stop or start the next plan
(``Executive.operator``):

* **skip** the running step: it is marked done (in the report and for checkpoints),
  with its effects applied to the belief or not, and the rest of the plan goes on;
  without its effects the next step may be found invalid, and the ordinary
  validate -> repair -> replan ladder takes over;
* **replan** from the current belief (it counts as a replan of the budget);
* **change the goal**: plan from the current belief to the new goal (ground atoms);
  from then on the mission succeeds when the new goal holds;
* **abort**: the running step is preempted and the mission ends ``aborted``.

One request is pending at a time: a later request replaces an earlier one, except
that an abort is never replaced. A request is taken at the latest when the plan in
force ends. Every request is recorded through the tree's controller (when one is
attached) so the journal shows what, from where and when.

The executive carries out a request through its public operator interface
(:meth:`~plan_bridge.execution.executive.Executive.skip_step`, ``replan_now``,
``running_steps``, ``stop_plan``, ``decide``).
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from plan_bridge.errors import FactError, PlanBridgeError
from plan_bridge.execution.replanner import MissionEnded
from plan_bridge.execution.steps import StepState
from plan_bridge.pddl.source import SourceText
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask, format_fact, parse_fact
from plan_bridge.pddl.up_runtime import ensure_unified_planning
from smach.control import Controller, ControlRecord, controller_of

if TYPE_CHECKING:
    from plan_bridge.execution.executive import Executive
    from plan_bridge.planning.types import PlanStep

__all__ = [
    "MissionControl",
    "MissionControlError",
    "OperatorConsole",
    "OperatorRequest",
    "parse_goal",
    "task_with_goal",
]

RequestKind = Literal["skip", "replan", "goal", "abort"]


class MissionControlError(PlanBridgeError, ValueError):
    """An operator request that cannot be carried out (what, where, what is allowed).

    A ValueError, as a refused request is one: the viewer answers 400, ROS ``False``.
    """


@dataclass(frozen=True)
class OperatorRequest:
    """A pending operator request (see the module documentation)."""

    kind: RequestKind
    source: str
    reason: str
    step_index: int | None = None
    apply_effects: bool = False
    task: PlanningTask | None = None


def task_with_goal(task: PlanningTask, goal: Iterable[FactLike]) -> PlanningTask:
    """A copy of ``task`` whose goal is the conjunction of the ground atoms ``goal``.

    Raises :class:`FactError` for an atom that does not fit the task (unknown
    predicate or object, wrong arity or type) and for an empty goal.
    """
    atoms = tuple(sorted({task.check_fact(f) for f in goal}))
    if not atoms:
        raise FactError("a goal needs at least one atom, e.g. (at robot1 kitchen)")
    ensure_unified_planning()
    problem = task.problem.clone()
    problem.clear_goals()
    # Built with the problem's own expression manager: no unified_planning import here.
    manager = problem.environment.expression_manager
    problem.add_goal(
        manager.And(
            *(problem.fluent(atom[0])(*(problem.object(arg) for arg in atom[1:])) for atom in atoms)
        )
    )
    text = None
    if task.problem_text is not None:
        source = SourceText(task.problem_text, str(task.problem_path or "<problem>"), "problem")
        body = " ".join("(" + " ".join(atom) + ")" for atom in atoms)
        for head, start, end in source.sections():
            if head == ":goal":
                text = source.text[:start] + f"(:goal (and {body}))" + source.text[end:]
                break
    spec = None if task.spec is None else task.spec.with_state(goal=atoms)
    return dataclasses.replace(
        task,
        problem=problem,
        goal_facts=atoms,
        goal_is_conjunctive=True,
        problem_text=text,
        spec=spec,
    )


def parse_goal(text: str | Iterable[FactLike]) -> list[Fact]:
    """``"(at r1 lab) (holding r1 cup)"`` or a list of facts -> facts."""
    if not isinstance(text, str):
        return [parse_fact(f) for f in text]
    facts: list[Fact] = []
    depth = 0
    start = 0
    for i, ch in enumerate(text):
        if ch == "(":
            if depth == 0:
                start = i
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth < 0:
                raise FactError(f"goal {text!r}: unbalanced ')' at column {i + 1}")
            if depth == 0:
                facts.append(parse_fact(text[start : i + 1]))
        elif depth == 0 and not ch.isspace():
            raise FactError(
                f"goal {text!r}: expected atoms in parentheses like (at robot1 kitchen), "
                f"found {ch!r} at column {i + 1}"
            )
    if depth:
        raise FactError(f"goal {text!r}: unbalanced '('")
    return facts


class MissionControl:
    """Skip, replan, new goal and abort for one :class:`Executive` (from any thread)."""

    def __init__(self, executive: Executive, controller: Controller | None = None) -> None:
        if executive.operator is not None:
            raise MissionControlError(f"executive {executive.path} already has a MissionControl")
        self.executive = executive
        self._controller = controller
        self._lock = threading.Lock()
        self._pending: OperatorRequest | None = None
        executive.operator = self

    def close(self) -> None:
        """Detach from the executive (a pending request is dropped)."""
        with self._lock:
            self._pending = None
        if self.executive.operator is self:
            self.executive.operator = None

    @property
    def controller(self) -> Controller | None:
        return self._controller or controller_of(self.executive)

    # -- requests --------------------------------------------------------------------------
    def skip(
        self, step: str | int | None = None, *, apply_effects: bool, source: str = "api"
    ) -> OperatorRequest:
        """Skip the running step (or the running one named by label or plan index)."""
        state = self._running_step(step)
        effects = "with its effects" if apply_effects else "without its effects"
        return self._request(
            OperatorRequest(
                "skip",
                source,
                f"operator ({source}) skipped {state.ground.step} {effects}",
                step_index=state.index,
                apply_effects=apply_effects,
            ),
            state.path,
        )

    def replan(self, *, source: str = "api") -> OperatorRequest:
        """Replan from the current belief now."""
        self._check_running()
        return self._request(
            OperatorRequest("replan", source, f"operator ({source}) asked for a replan")
        )

    def change_goal(
        self, goal: str | Iterable[FactLike], *, source: str = "api"
    ) -> OperatorRequest:
        """Plan from the current belief to ``goal`` (atoms, or text ``"(at r1 lab) ..."``)."""
        self._check_running()
        atoms = parse_goal(goal)
        task = task_with_goal(self.executive.task, atoms)
        shown = " ".join(format_fact(f) for f in task.goal_facts)
        return self._request(
            OperatorRequest(
                "goal", source, f"operator ({source}) changed the goal to {shown}", task=task
            )
        )

    def abort(self, reason: str = "", *, source: str = "api") -> OperatorRequest:
        """End the mission ``aborted`` after the running step stops."""
        self._check_running()
        why = f": {reason}" if reason else ""
        return self._request(
            OperatorRequest("abort", source, f"aborted by the operator ({source}){why}")
        )

    def pending(self) -> OperatorRequest | None:
        with self._lock:
            return self._pending

    # -- the executive's hook ----------------------------------------------------------------
    def take(self, executive: Executive, plan: list[PlanStep]) -> list[PlanStep]:
        """Carry out the pending request (in the executive's thread); the plan to run next.

        Raises :class:`MissionEnded` for an abort, when a new goal already holds, and
        when no plan reaches the (new) goal.
        """
        with self._lock:
            request, self._pending = self._pending, None
        if request is None:
            return plan
        executive.decide("operator", request.reason)
        if request.kind == "abort":
            raise MissionEnded("aborted", request.reason)
        if request.kind == "skip":
            assert request.step_index is not None
            return executive.skip_step(request.step_index, apply_effects=request.apply_effects)
        return executive.replan_now(request.reason, request.task)

    # -- internals -----------------------------------------------------------------------------
    def _check_running(self) -> None:
        if not self.executive.is_running():
            raise MissionControlError(
                f"executive {self.executive.path}: the mission is not running; skip, replan, "
                f"goal and abort act on a running mission"
            )

    def _running_step(self, step: str | int | None) -> StepState:
        self._check_running()
        running = self.executive.running_steps()
        if step is None:
            if len(running) == 1:
                return running[0]
            if not running:
                raise MissionControlError(
                    f"executive {self.executive.path}: no step is running (planning, or "
                    f"between steps); try again or name a step"
                )
            raise MissionControlError(
                f"executive {self.executive.path}: {len(running)} steps are running ("
                + ", ".join(s.path.rsplit("/", 1)[-1] for s in running)
                + "); name one"
            )
        for state in running:
            label = state.path.rsplit("/", 1)[-1]
            if step in (state.index, label, str(state.index)):
                return state
        names = ", ".join(f"{s.index} ({s.path.rsplit('/', 1)[-1]})" for s in running) or "none"
        raise MissionControlError(
            f"executive {self.executive.path}: step {step!r} is not running; running: {names}"
        )

    def _request(self, request: OperatorRequest, path: str = "") -> OperatorRequest:
        with self._lock:
            pending = self._pending
            if pending is not None and pending.kind == "abort":
                raise MissionControlError(
                    f"executive {self.executive.path}: an abort is already pending; "
                    f"{request.kind} refused"
                )
            self._pending = request
        controller = self.controller
        if controller is not None:
            details: dict[str, object] = {"reason": request.reason}
            if pending is not None:
                details["replaces"] = pending.kind
            if request.kind == "skip":
                details["apply_effects"] = request.apply_effects
            if request.task is not None:
                details["goal"] = [format_fact(f) for f in request.task.goal_facts]
            controller.note(
                request.kind, source=request.source, path=path or self.executive.path, **details
            )
        # The plan in force stops at once (its running steps are preempted); when no
        # plan runs yet, the executive takes the request before it starts the next one.
        self.executive.stop_plan()
        return request


class OperatorConsole:
    """Everything an operator needs on a running executive, wired in one call.

    A :class:`~smach.control.Controller` on the executive (pause, step, breakpoints,
    force outcome), a :class:`MissionControl` (skip, replan, goal, abort) and every
    control action written to ``journal`` as a ``control`` record. For a viewer,
    pass :meth:`viewer_actions` to ``smach.introspection.control_api.enable_controls``.
    """

    def __init__(
        self,
        executive: Executive,
        *,
        journal: Any = None,
        breakpoints: Iterable[str] = (),
        paused: bool = False,
        source: str = "cli",
    ) -> None:
        existing = controller_of(executive)
        self.controller = existing if existing is not None else Controller(executive)
        self._own_controller = existing is None
        self.mission = MissionControl(executive, self.controller)
        self.journal = journal
        if journal is not None:
            self.controller.add_observer(self._write)
        for pattern in breakpoints:
            self.controller.add_breakpoint(pattern, source=source)
        if paused:
            self.controller.pause(source=source)
        self.executive = executive

    def _write(self, record: ControlRecord) -> None:
        self.journal.write_record("control", **record.to_json())

    def viewer_actions(self) -> dict[str, Callable[[Mapping[str, Any]], object]]:
        """The mission's actions for the viewer, the CLI and ROS (``source`` from the body)."""
        mission = self.mission

        def source(body: Mapping[str, Any]) -> str:
            value = body.get("source", "viewer")
            return value if value in ("viewer", "cli", "ros") else "viewer"

        def skip(body: Mapping[str, Any]) -> object:
            effects = body.get("apply_effects")
            if not isinstance(effects, bool):
                raise ValueError("skip needs 'apply_effects': true or false")
            step = body.get("step")
            if step is not None and not isinstance(step, str | int):
                raise ValueError(f"'step' is a step label or index, got {step!r}")
            return mission.skip(step, apply_effects=effects, source=source(body)).reason

        def goal(body: Mapping[str, Any]) -> object:
            text = body.get("goal")
            if not isinstance(text, str) or not text.strip():
                raise ValueError("goal needs 'goal': atoms like (at robot1 kitchen)")
            return mission.change_goal(text, source=source(body)).reason

        def reason(body: Mapping[str, Any]) -> str:
            text = body.get("reason", "")
            return text[:500] if isinstance(text, str) else ""

        return {
            "skip": skip,
            "replan": lambda body: mission.replan(source=source(body)).reason,
            "goal": goal,
            "abort": lambda body: mission.abort(reason(body), source=source(body)).reason,
        }

    def close(self) -> None:
        self.mission.close()
        if self.journal is not None:
            self.controller.remove_observer(self._write)
        if self._own_controller:
            self.controller.close()
