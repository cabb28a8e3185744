"""The executive: plan, compile, run, and recover from failures by the policy.

The :class:`Executive` is a ``smach`` container (so it nests in hand-written machines
and shows up in introspection as ``.../PLAN/03_PICK_CUP_TABLE/SKILL``). It stops early
when the goal already holds; otherwise it plans (:mod:`.replanner`), runs the compiled
plan, and after a failed or invalid step follows the recovery ladder of
:mod:`.repair` (a list of strategies: continue, retry, variant, redo, repair, replan
and hold by default) within the policy's budgets
(:mod:`.policy`). Every decision is an
:class:`~plan_bridge.execution.events.ExecutiveDecision` event with its reason.

(Over 600 lines: the mission loop, the operator's and the knowledge base's hooks
(:mod:`.control`, :mod:`.knowledge_link`) and the checkpoints share the plan in force,
the belief and the task of one container; split, each part would reach into the
others' state.)
"""

from __future__ import annotations

import bisect
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import smach
from plan_bridge.belief import Belief, Observation, describe_observation, normalise_observations
from plan_bridge.belief.whereabouts import ABSENT, places_of
from plan_bridge.errors import FactError, PlanBridgeError
from plan_bridge.execution.compile import compile_plan
from plan_bridge.execution.events import ExecutiveDecision, PlanComputed
from plan_bridge.execution.plan_cache import PlanCache
from plan_bridge.execution.policy import ExecutionReport, ReplanPolicy
from plan_bridge.execution.repair import Recovery, RecoveryStrategy, default_ladder
from plan_bridge.execution.replanner import MissionEnded, Replanner
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.steps import (
    CompiledPlan,
    PlanContainer,
    PlanHold,
    StepRecord,
    StepState,
)
from plan_bridge.execution.task_view import TaskView, adopt_map_atoms
from plan_bridge.execution.temporal import TemporalDispatch
from plan_bridge.execution.world import World
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact, parse_fact
from plan_bridge.planning.registry import get_planner
from plan_bridge.planning.types import Planner, PlanResult, PlanStep
from plan_bridge.skills.registry import SkillRegistry
from smach.introspection.events import Event, stamp

if TYPE_CHECKING:
    from plan_bridge.execution.knowledge_link import KnowledgeLink
    from plan_bridge.pddl.knowledge import KnowledgeBase

__all__ = ["ExecutionReport", "Executive", "Operator", "ReplanPolicy"]

OUTCOMES = ("succeeded", "aborted", "preempted")


class Operator(Protocol):
    """What the executive asks of an operator's requests where its loop would stop or
    start the next plan (:class:`~plan_bridge.execution.control.MissionControl`)."""

    def pending(self) -> object | None:
        """The request waiting to be taken, if any."""

    def take(self, executive: Executive, plan: list[PlanStep]) -> list[PlanStep]:
        """Carry out the request waiting (in the executive's thread); the plan to run next."""


class Executive(PlanContainer):
    """Plans for ``task`` and executes the plan with ``skills``, replanning on failure.

    Outcomes: ``succeeded`` (goal reached), ``aborted`` (no plan, budget exhausted,
    unrecoverable), ``preempted``. After a run, :attr:`report` holds the numbers and
    ``report.explanation`` says why the mission ended (always set).

    The defaults are those of ``plan-bridge run``: planner ``auto`` (chosen by the
    problem's kind: Fast Downward for classical problems, Kairos or TAMER for temporal
    and numeric ones) and the ``full`` recovery policy. ``world`` is the
    :class:`~plan_bridge.execution.world.World` the skills act on; by default the one
    the registry's simulated skills act on (``symbolic_skills(world, registry)``), if
    any. It learns what the user's own skills did and is sensed after a failure that
    observed nothing (docs/plan-bridge.md, "The skill contract").

    ``knowledge``: a :class:`~plan_bridge.pddl.knowledge.KnowledgeBase` holding the
    problem (:meth:`attach_knowledge`): the belief is its facts, and the mission
    follows its objects and goal (a change of them stops the plan and replans).

    ``recovery_ladder``: the recovery strategies tried in order after a failure
    (:class:`~plan_bridge.execution.repair.RecoveryStrategy`; by default
    :func:`~plan_bridge.execution.repair.default_ladder`), kept in
    :attr:`recovery_ladder`.
    """

    #: Operator requests (skip, replan, new goal, abort): see execution/control.py.
    operator: Operator | None = None

    def __init__(
        self,
        task: PlanningTask,
        skills: SkillRegistry,
        planner: Planner | str = "auto",
        *,
        world: World | None = None,
        policy: ReplanPolicy | None = None,
        belief: Belief | None = None,
        sense: Callable[[Belief], Iterable[Any]] | None = None,
        concurrent: bool = False,
        check_preconditions: bool = True,
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        checkpoint: Callable[[dict[str, Any]], None] | None = None,
        plan_cache: PlanCache | None = None,
        knowledge: KnowledgeBase | None = None,
        recovery_ladder: Sequence[RecoveryStrategy] | None = None,
        task_view: TaskView | None = None,
    ) -> None:
        super().__init__(list(OUTCOMES), input_keys, output_keys)
        #: Called (from the step's thread) after every succeeded step with the state
        #: needed to resume: see :meth:`resume_from` and docs/reliability.md.
        self.checkpoint = checkpoint
        self._resume: dict[str, Any] | None = None
        self._resume_plan_zero: float | None = None
        self._checkpoint_lock = threading.Lock()
        self._plan_in_force: list[PlanStep] = []
        self._first_in_force = 1
        self._executed: list[tuple[int, str]] = []
        self.task = task
        self.skills = skills
        self.world = world if world is not None else skills.world
        self.planner = get_planner(planner) if isinstance(planner, str) else planner
        self.policy = policy or ReplanPolicy()
        #: The recovery strategies tried in order after a failure (execution/repair.py):
        #: :func:`~plan_bridge.execution.repair.default_ladder` unless given.
        self.recovery_ladder: list[RecoveryStrategy] = (
            default_ladder() if recovery_ladder is None else list(recovery_ladder)
        )
        self.model = ActionModel(task)
        #: Makes the task to plan from the belief (a world with a map: execution/task_view.py).
        self.task_view = task_view
        # The goal a knowledge base of the whole world set (its task: the view's).
        self._goal: tuple[Fact, ...] = ()
        # The places the belief says lost objects are not (a search's progress).
        self._searched = 0
        # Why the plan in force was stopped for a search (a lost object found while
        # other steps still look for it elsewhere, or a place ruled out while other
        # robots' steps run: _search_over), or "".
        self._found = ""
        if belief is not None:
            self.belief = belief
        elif task_view is not None:
            self.belief = Belief(task_view.belief(), whereabouts=True)
            adopt_map_atoms(task_view, self.belief, task, self.model.initial_values())
        else:
            self.belief = Belief(task.initial_facts, self.model.initial_values())
        #: Temporal plans: wall seconds per plan second (0: start steps on events only)
        #: and what happens to running steps when one fails (``finish`` or ``preempt``).
        self.time_scale = 0.0
        self.on_failure = "finish"
        self.sense = sense
        self.concurrent = concurrent
        self.check_preconditions = check_preconditions
        #: Plans found per (state, goal); share one between executives of the same
        #: problem to reuse plans across missions (``ReplanPolicy.reuse_plans``).
        self.plan_cache = plan_cache if plan_cache is not None else PlanCache()
        self.report = ExecutionReport()
        self._compiled: CompiledPlan | None = None
        self._replanner: Replanner | None = None
        self._recovery: Recovery | None = None
        self._records: dict[int, StepRecord] = {}
        self._in_mission = False  # between the start and the end of run_children
        #: Stops the plan in force from starting steps, its running steps finishing
        #: (:class:`~plan_bridge.execution.steps.PlanHold`; what orders use).
        self.hold = PlanHold()
        #: The knowledge base the mission follows (None: the task's problem).
        self.knowledge: KnowledgeBase | None = None
        self._link: KnowledgeLink | None = None
        if knowledge is not None:
            self.attach_knowledge(knowledge)

    # -- Container interface ---------------------------------------------------------------
    def get_children(self) -> dict[str, smach.State]:
        return {"PLAN": self._compiled.machine} if self._compiled is not None else {}

    def get_initial_states(self) -> list[str]:
        return ["PLAN"] if self._compiled is not None else []

    def get_active_states(self) -> list[str]:
        return ["PLAN"] if self._in_mission and self._compiled is not None else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        if self._compiled is None:
            return []
        edges: list[tuple[str, str, str | None]] = [(o, "PLAN", o) for o in OUTCOMES]
        return [*edges, ("aborted", "PLAN", "PLAN"), ("invalid", "PLAN", "PLAN")]

    def consistency_problems(self) -> list[str]:
        # Plans are compiled (and checked) at run time; the skills check builds every
        # skill once, so it runs on demand (check_consistency, `plan-bridge check`).
        return []

    def check_consistency(self) -> None:
        problems = self.skills.check(self.task)
        if problems:
            raise smach.InvalidStateError(
                f"executive {self.path}: skills do not fit the domain:\n  " + "\n  ".join(problems)
            )

    def request_preempt(self) -> None:
        super().request_preempt()
        compiled = self._compiled
        if self.is_running() and compiled is not None:
            compiled.machine.request_preempt()

    # -- execution -------------------------------------------------------------------------
    def run_children(self) -> str | None:
        """Run the mission; return succeeded / aborted / preempted.

        Called by ``smach.Container.execute``, the run protocol every container shares
        (input/output keys, started/terminated/error events, preempt bookkeeping).
        """
        started = time.monotonic()
        self.report = report = ExecutionReport()
        # The next step label, and the succeeded steps in plan order.
        self._next_label = 1
        self._executed = []
        self._in_mission = True
        try:
            outcome = self._mission()
            report.explanation = report.explanation or "goal reached"
        except MissionEnded as stop:
            outcome, report.explanation = stop.outcome, stop.explanation
        finally:
            self._in_mission = False
        report.outcome = outcome
        report.goal_reached = self.model.goal_holds(self.belief.facts)
        report.total_time_s = time.monotonic() - started
        report.execution_time_s = max(0.0, report.total_time_s - report.planning_time_s)
        return outcome

    def _start_states(self) -> list[str]:
        return ["PLAN"]

    def _terminal_states(self) -> list[str]:
        return ["PLAN"]

    def _mission(self) -> str:
        resume, self._resume = self._resume, None
        if resume is not None:
            plan, self._next_label = self._restore(resume)
        recovery = self._begin_mission()
        self._sense()
        if self.model.goal_holds(self.belief.facts):
            self.decide("done", "the goal already holds")
            return "succeeded"
        self._retask()
        if resume is None:
            initial = recovery.replanner.plan("initial plan")
            if not initial.solved:
                raise MissionEnded(
                    "aborted", f"no plan ({initial.status.value}): {initial.explanation}"
                )
            plan = list(initial.actions)
        while True:
            self._check_preempt()
            if self.operator is not None:  # an operator request replaces the plan
                plan = self.operator.take(self, plan)
            if self._knowledge_pending():  # the knowledge base's objects or goal changed
                plan = self.replan_now("the knowledge base changed")
            if self._found:  # the others stop looking: the mission goes on from here
                found, self._found = self._found, ""
                self.decide("search", found)
                searched = self._searched
                plan = self.replan_now(found)
                if self._replanner is not None and self._searched == searched:
                    # A find ends a search: not a failure (a place ruled out was
                    # refunded when the task was made again).
                    self._replanner.budgeted_calls = max(0, self._replanner.budgeted_calls - 1)
            first = self._next_label
            outcome, failed = self._run_plan(plan, first)
            self._next_label = max(self._records, default=first - 1) + 1
            if self.operator is not None and self.operator.pending() is not None:
                continue  # the operator stopped this plan: take the request
            if self._knowledge_pending() or self._found:
                continue  # stopped for a change of the knowledge base, or a find: replan
            if outcome == "preempted":
                self.decide("stop", "preempted")
                return "preempted"
            self._sense(
                [
                    record.step
                    for record in self._records.values()
                    if record.outcome == "aborted" and record.by_user and not record.observed
                ]
            )
            if self.model.goal_holds(self.belief.facts):
                return "succeeded"
            reason, rest, record = self._what_failed(
                plan, first, failed, "the plan finished but the goal does not hold"
            )
            self._retask()
            plan = recovery.recover(rest, reason, record)

    def _begin_mission(self) -> Recovery:
        """Take the knowledge base's news, and make the replanner and the recovery of
        this run (the replanner is kept between runs: its portfolio is built once)."""
        news = self._take_knowledge()
        if news:
            self.decide("knowledge", f"planning for the knowledge base's problem ({news})")
        replanner = self._replanner
        if (
            replanner is None
            or replanner.planner is not self.planner
            or replanner.policy is not self.policy
            or replanner.cache is not self.plan_cache
        ):
            replanner = self._replanner = Replanner(
                self.task,
                self.planner,
                self.policy,
                self.model,
                self.belief,
                self.plan_cache,
                self.preempt_event,
                self._plan_computed,
                projected=self.task_view is not None,
            )
        replanner.start(self.report)
        recovery = self._recovery = Recovery(
            self.model,
            self.policy,
            self.belief,
            replanner,
            self.report,
            self.decide,
            self.skills,
            self.recovery_ladder,
        )
        return recovery

    def _run_plan(self, plan: list[PlanStep], first_index: int) -> tuple[str, int | None]:
        """Run ``plan``; return (outcome, index in ``plan`` of the first unfinished step)."""
        self._found = ""  # a search's stop is for the plan it stopped (orders replan anyway)
        compiled = compile_plan(
            plan,
            self.skills,
            self.model,
            self.belief,
            first_index=first_index,
            concurrent=self.concurrent,
            check_preconditions=self.check_preconditions,
            on_finished=self._step_finished,
            time_scale=self.time_scale or (self.world.time_scale if self.world else 0.0),
            on_failure=self.on_failure,
            variants=self._recovery.variants_of(plan) if self._recovery is not None else None,
            world=self.world,
            on_started=self._step_started,
            hold=self.hold,
        )
        self._compiled = compiled
        if isinstance(compiled.machine, TemporalDispatch):
            # The first plan of a resumed run keeps the killed run's timeline.
            compiled.machine.plan_zero, self._resume_plan_zero = self._resume_plan_zero, None
        self.replace_child("PLAN", compiled.machine)
        self._records = {}
        self._plan_in_force, self._first_in_force = plan, first_index
        self.report.final_plan = [str(s) for s in plan]
        if self.preempt_requested() or self._knowledge_pending():
            compiled.machine.request_preempt()
        ud = smach.Remapper(
            self.userdata,
            compiled.machine.get_registered_input_keys(),
            compiled.machine.get_registered_output_keys(),
            owner=self,
            writer="PLAN",
        )
        outcome = compiled.machine.execute(ud)
        if outcome == "preempted" or self.preempt_requested():
            return "preempted", None
        if outcome == "succeeded":
            return "succeeded", None
        unfinished = [i for i in range(len(plan)) if not self._succeeded(first_index + i)]
        failed = [
            i
            for i in unfinished
            if first_index + i in self._records
            and self._records[first_index + i].outcome in ("aborted", "invalid")
        ]
        if failed:
            return outcome or "aborted", failed[0]
        return outcome or "aborted", unfinished[0] if unfinished else None

    def _succeeded(self, index: int) -> bool:
        record = self._records.get(index)
        return record is not None and record.outcome == "succeeded"

    def _step_started(self, index: int, step: PlanStep) -> None:
        """Step ``index`` (``step``) of the plan in force starts (in its thread)."""

    def _step_finished(self, record: StepRecord) -> None:
        with self._checkpoint_lock:
            self._records[record.index] = record
            report = self.report
            if record.outcome != "invalid":
                report.actions_executed += 1
            if record.outcome == "succeeded":
                # In plan order (labels only grow), whatever order concurrent steps end in.
                bisect.insort(self._executed, (record.index, str(record.step)))
                report.executed = [step for _, step in self._executed]
            elif record.outcome in ("aborted", "invalid"):
                report.actions_failed += 1
            if record.outcome == "succeeded" and self.checkpoint is not None:
                self.checkpoint(self.snapshot())
            if not self._found:
                self._found = self._search_over(record)
                if self._found:
                    self.stop_plan()

    def _search_over(self, record: StepRecord) -> str:
        """Why the plan in force stops after ``record``'s step, for a search: a lost
        object was found while steps of the plan still look for it elsewhere (another
        robot's ``search``), or a place a step was to look at was ruled out while other
        robots' steps run (they need not finish before the robots look further); or
        ``""``."""
        pending = [
            step
            for i, step in enumerate(self._plan_in_force, start=self._first_in_force)
            if step.action.lower() == "search"
            and len(step.arguments) > 2
            and not self._succeeded(i)
        ]
        if not pending:
            return ""
        facts = self.belief.facts
        at, held = places_of(facts)
        for step in pending:
            item, place = step.arguments[1].lower(), step.arguments[2].lower()
            where = sorted(at.get(item, ())) or ([f"{held[item]}'s hand"] if item in held else [])
            if where and place not in where:
                return f"{item} found at {where[0]}: {step.arguments[0]} stops looking at {place}"
        others = [
            state
            for state in self.running_steps()
            if state.index != record.index
            and state.ground.step.arguments[:1] != record.step.arguments[:1]
        ]
        for step in pending if others else ():
            item, place = step.arguments[1].lower(), step.arguments[2].lower()
            if (ABSENT, item, place) in facts:
                return f"{item} is not at {place}: the robots look further"
        return ""

    # -- operator requests (MissionControl, execution/control.py) --------------------------
    def running_steps(self) -> list[StepState]:
        """The steps of the plan in force whose skills are running now."""
        compiled = self._compiled
        return [s for s in compiled.step_states if s.is_running()] if compiled else []

    def stop_plan(self) -> None:
        """Preempt the plan in force (its running steps); the mission loop goes on."""
        compiled = self._compiled
        if compiled is not None:
            compiled.machine.request_preempt()

    def skip_step(self, index: int, *, apply_effects: bool) -> list[PlanStep]:
        """Mark step ``index`` of the plan in force done (its effects applied to the
        belief or not); return the rest of that plan."""
        first, in_force = self._first_in_force, self._plan_in_force
        if first <= index < first + len(in_force) and not self._succeeded(index):
            step = in_force[index - first]
            if apply_effects:
                ground = self.model.ground(step)
                with self.belief.locked() as facts:
                    adds, dels = ground.effects(facts)
                self.belief.apply(adds, dels)
            self._step_finished(
                StepRecord(index, step, outcome="succeeded", skill_outcome="skipped")
            )
        return [
            step
            for i, step in enumerate(in_force, start=first)
            if i != index and not self._succeeded(i)
        ]

    def replan_now(self, reason: str, task: PlanningTask | None = None) -> list[PlanStep]:
        """Plan from the belief now (to ``task``'s goal from then on, if given): one
        replan of the budget. Raises :class:`MissionEnded` when the goal holds or no
        plan reaches it."""
        replanner, recovery = self._replanner, self._recovery
        if replanner is None or recovery is None:
            raise RuntimeError(f"executive {self.path}: replan_now is for a running mission")
        operator_goal = task is not None and self.knowledge is not None
        if task is not None and self.knowledge is not None:
            # The goal lives in the knowledge base: it takes the new one, and the
            # mission plans for the knowledge base's problem.
            try:
                self.knowledge.set_goal(task.goal_facts, source="operator")
            except FactError as exc:  # it changed since the request was checked
                self.decide("knowledge", f"the knowledge base refused the goal: {exc}")
            task = None
        news = self._take_knowledge()
        if news and not operator_goal:
            reason = f"{reason}: {news}"
            self.decide("knowledge", reason)
        if task is not None:
            self._use_task(task)
        self._retask()
        if self.model.goal_holds(self.belief.facts):
            raise MissionEnded("succeeded", f"{reason}; the goal holds")
        result = replanner.plan(reason, replan=True)
        if not result.solved:
            raise MissionEnded(
                "aborted", f"{reason}: no plan ({result.status.value}): {result.explanation}"
            )
        self.report.replans += 1
        recovery.generation += 1  # retries are counted per plan
        return list(result.actions)

    # -- the knowledge base (execution/knowledge_link.py) ------------------------------------
    def attach_knowledge(self, knowledge: KnowledgeBase) -> None:
        """Follow ``knowledge``: its facts become the belief's; a change of its objects
        or goal stops the plan in force and replans; an operator's new goal goes into it."""
        from plan_bridge.execution.knowledge_link import KnowledgeLink

        if self.is_running():
            raise RuntimeError(f"executive {self.path}: attach a knowledge base before the run")
        self.detach_knowledge()
        view = self.task_view
        self._link = KnowledgeLink(
            knowledge,
            self.belief,
            self.task,
            self._knowledge_changed,
            whole_world=view is not None,
            objects_of=view.objects if view is not None else None,
        )
        self.knowledge = knowledge

    def detach_knowledge(self) -> None:
        """Stop following the knowledge base (it keeps a copy of the facts)."""
        if self._link is not None:
            self._link.close()
        self._link, self.knowledge = None, None

    def _knowledge_changed(self) -> None:
        if self.is_running():
            self.stop_plan()

    def _take_knowledge(self) -> str:
        """What changed in the knowledge base (the task is rebuilt from it), or ``""``."""
        try:
            news, task = self._link.take() if self._link is not None else ("", None)
        except PlanBridgeError as exc:  # its problem does not load (a bug of ours, or UP's)
            raise MissionEnded("aborted", f"the knowledge base's problem: {exc}") from exc
        if task is not None:
            self._use_task(task)
        elif news and self._link is not None and self._link.whole_world:
            # The view makes the task of the knowledge base's goal from the belief.
            self._goal = tuple(self._link.knowledge.goal)
            self._retask()
        return news

    def _knowledge_pending(self) -> bool:
        return self._link is not None and self._link.changed

    def _retask(self) -> None:
        """With a task view: plan the task it makes of the belief now (its map atoms
        go into the belief when it is another task)."""
        view = self.task_view
        if view is None:
            return
        facts = self.belief.facts
        searched = sum(1 for f in facts if f[0] == ABSENT)
        if searched > self._searched and self._replanner is not None:
            # A place where a lost object is not is what a search is for, not a failure:
            # the replan that looks further is not counted against the budget.
            self._replanner.budgeted_calls = max(0, self._replanner.budgeted_calls - 1)
        self._searched = searched
        try:
            task = view.task_for(facts, self._goal or self.task.goal_facts)
        except PlanBridgeError as exc:
            # A verdict (an object in none of the places it may be in) is the reason.
            why = str(exc) if getattr(exc, "verdict", False) else f"no task for the belief: {exc}"
            raise MissionEnded("aborted", why) from exc
        if task is self.task:
            return
        self._use_task(task)
        adopt_map_atoms(view, self.belief, task, self.model.initial_values())

    def _use_task(self, task: PlanningTask) -> None:
        self.task, self.model = task, ActionModel(task)
        if self._replanner is not None:
            self._replanner.task, self._replanner.model = task, self.model
        if self._recovery is not None:
            self._recovery.model = self.model

    # -- checkpoints ------------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        """What a resumed run needs: the plan still to do, the belief, the numbers so far.

        "Done" means a step whose skill succeeded and whose effects were applied to the
        belief; a step that was running when the process died is not done and runs
        again after its preconditions are checked against the (restored) belief.
        """
        first = self._first_in_force
        remaining = [
            str(step)
            for i, step in enumerate(self._plan_in_force, start=first)
            if not self._succeeded(i)
        ]
        done = [i for i in range(first, first + len(self._plan_in_force)) if self._succeeded(i)]
        snapshot = {
            "plan": remaining,
            "first_index": max(done, default=first - 1) + 1,
            "belief": sorted(format_fact(f) for f in self._settled_facts()),
            "report": self.report.to_json(),
            "userdata": _json_values(self.userdata),
        }
        # Temporal plans and numbers: the steps' planned times, the numeric fluents.
        if any(step.start is not None for step in self._plan_in_force):
            snapshot["timing"] = [
                [step.start, step.duration]
                for i, step in enumerate(self._plan_in_force, start=first)
                if not self._succeeded(i)
            ]
        values = self.belief.values
        if values:
            snapshot["values"] = sorted([format_fact(f), v] for f, v in values.items())
        machine = None if self._compiled is None else self._compiled.machine
        if isinstance(machine, TemporalDispatch):
            zero = machine.plan_zero_now()
            if zero is not None:  # a simulated clock: the resumed run keeps the timeline
                snapshot["plan_zero"] = zero
        return snapshot

    def _settled_facts(self) -> frozenset[Fact]:
        compiled = self._compiled
        if compiled is not None and compiled.settled_facts is not None:
            return compiled.settled_facts()
        return frozenset(self.belief.facts)

    def resume_from(self, snapshot: dict[str, Any]) -> None:
        """Make the next :meth:`execute` continue from a :meth:`snapshot` (no initial plan)."""
        for key in ("plan", "first_index", "belief", "report"):
            if key not in snapshot:
                raise ValueError(f"not an executive snapshot: the {key!r} entry is missing")
        self._resume = dict(snapshot)

    def _restore(self, snapshot: dict[str, Any]) -> tuple[list[PlanStep], int]:
        values = {parse_fact(f): float(v) for f, v in snapshot.get("values", ())}
        self.belief.replace(
            (parse_fact(f) for f in snapshot["belief"]), values if "values" in snapshot else None
        )
        saved = snapshot["report"]
        report = self.report
        for name in (
            "actions_executed",
            "actions_failed",
            "retries",
            "variants_tried",
            "continues",
            "repairs",
            "replans",
            "planner_calls",
            "plans_reused",
            "holds",
            "planning_time_s",
        ):
            setattr(report, name, saved.get(name, 0))
        report.planners_won = dict(saved.get("planners_won", {}))
        report.executed = list(saved.get("executed", []))
        self._executed = [
            (-len(report.executed) + i, step) for i, step in enumerate(report.executed)
        ]
        report.decisions = list(saved.get("decisions", []))
        for key, value in snapshot.get("userdata", {}).items():
            self.userdata[key] = value
        plan = [PlanStep(f[0], tuple(f[1:])) for f in (parse_fact(s) for s in snapshot["plan"])]
        timing = snapshot.get("timing")
        if isinstance(timing, list) and len(timing) == len(plan):
            plan = [
                PlanStep(step.action, step.arguments, start, duration)
                for step, (start, duration) in zip(plan, timing, strict=True)
            ]
        zero = snapshot.get("plan_zero")
        self._resume_plan_zero = float(zero) if isinstance(zero, int | float) else None
        self.decide("resume", f"resuming with {len(plan)} steps left from a checkpoint")
        return plan, int(snapshot["first_index"])

    def _what_failed(
        self, plan: Sequence[PlanStep], first: int, failed: int | None, finished: str
    ) -> tuple[str, list[PlanStep], StepRecord | None]:
        """Why the plan (its steps labelled from ``first``) stopped, the steps to
        recover (the failed one first, then every other one not done yet: with
        concurrent layers, later steps may be done and same-layer ones not), and the
        failed step's record. ``failed`` None: the plan finished, ``finished`` says
        what does not hold."""
        if failed is None:
            unmet = ", ".join(self.model.unmet_goals(self.belief.facts))
            return f"{finished}: {unmet}", [], None
        record = self._records.get(first + failed)
        rest = [plan[failed]] + [
            step for i, step in enumerate(plan) if i != failed and not self._succeeded(first + i)
        ]
        return self._failure_reason(plan[failed], record), rest, record

    def _failure_reason(self, step: PlanStep, record: StepRecord | None) -> str:
        if record is None:
            return f"{step} did not run"
        if record.outcome == "invalid":
            return f"{step} cannot start: unmet preconditions {', '.join(record.unmet)}"
        detail = (
            f" (skill outcome {record.skill_outcome!r})"
            if record.skill_outcome and record.skill_outcome != record.outcome
            else ""
        )
        seen = (
            f"; observed {', '.join(record.observations_changed)}"
            if record.observations_changed
            else ""
        )
        return f"{step} {record.outcome}{detail}{seen}"

    def _plan_computed(self, reason: str, result: PlanResult) -> None:
        self._announce(
            PlanComputed,
            reason=reason,
            planner=result.planner,
            status=result.status.value,
            steps=tuple(str(s) for s in result.actions),
            planning_time_s=result.planning_time_s,
            explanation=result.explanation,
            makespan=result.makespan,
        )

    def _announce(self, kind: Callable[..., Event], **fields: Any) -> None:
        """Emit the executive's event ``kind`` with ``fields`` (its path, the time and
        the thread filled in), if anybody listens."""
        if self.is_observed():
            t, thread = stamp()
            self.emit_event(kind(path=self.path, time=t, thread=thread, **fields))

    # -- belief --------------------------------------------------------------------------------
    def _sense(self, unobserved: Sequence[PlanStep] = ()) -> None:
        """Refresh the belief: the world is sensed around steps that failed without
        observing anything (a user's skill that just said "aborted"), then the
        ``sense`` callback, if any, runs."""
        if self.world is not None and unobserved:
            changed = self.belief.observe(self.world.sense(unobserved))
            seen = ", ".join(describe_observation(f, v) for f, v in changed) or "nothing new"
            steps = ", ".join(str(step) for step in unobserved)
            self.decide("sense", f"{steps} failed without observing; sensed: {seen}")
        if self.sense is None:
            return
        observations: list[Observation] = normalise_observations(self.sense(self.belief))
        self.belief.observe(observations)

    def _check_preempt(self) -> None:
        if self.preempt_requested():
            raise MissionEnded("preempted", "preempted")

    def decide(self, decision: str, reason: str, step: str = "") -> None:
        self.report.decisions.append({"decision": decision, "reason": reason, "step": step})
        self._announce(ExecutiveDecision, decision=decision, reason=reason, step=step)


def _json_values(ud: smach.UserData) -> dict[str, Any]:
    """The userdata values that survive a round trip through JSON (others are skipped)."""
    import json

    out: dict[str, Any] = {}
    for key in ud:
        try:
            json.dumps(ud[key])
        except (TypeError, ValueError):
            continue
        out[key] = ud[key]
    return out
