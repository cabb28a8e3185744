"""The executive: plan, compile, run, and recover from failures by the policy.

The :class:`Executive` is a ``smach`` container (so it nests in hand-written machines
and shows up in introspection as ``.../PLAN/03_PICK_CUP_TABLE/SKILL``). On a failed or
invalid step it decides, in this order, within the policy's budgets:

1. **retry** the step, if its preconditions still hold (bounded per step);
2. **continue** with the rest of the plan, if it is still valid from the belief
   (e.g. the step's effects came true anyway);
3. **repair**: plan only a prefix that re-establishes what the rest of the plan
   needs (goal regression), then continue with the rest;
4. **replan** from the belief.

It stops early when the goal already holds. Every decision is an
:class:`~plan_bridge.execution.events.ExecutiveDecision` event with its reason.
"""

from __future__ import annotations

import bisect
import dataclasses
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import smach
from plan_bridge.execution.compile import CompiledPlan, StepRecord, compile_plan
from plan_bridge.execution.events import ExecutiveDecision, PlanComputed
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.world import Observation, WorldState, normalise_observations
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact, parse_fact
from plan_bridge.planning.planner import Planner, PlanResult, PlanStep, get_planner
from plan_bridge.skills.registry import SkillRegistry
from smach.introspection.events import stamp

__all__ = ["ExecutionReport", "Executive", "ReplanPolicy"]

OUTCOMES = ("succeeded", "aborted", "preempted")


@dataclass(frozen=True)
class ReplanPolicy:
    """How the executive recovers from failures, and its budgets."""

    max_step_retries: int = 1
    """Retries of one failed step while its preconditions still hold."""
    continue_if_valid: bool = True
    """Skip ahead when the rest of the plan is valid from the belief."""
    repair: bool = True
    """Try a repair prefix before a full replan (STRIPS-style plans only)."""
    repair_max_prefix_ratio: float = 0.5
    """Keep a repaired plan only if its new prefix is at most this fraction of the
    plan it rescues: a long detour means the old plan is a poor fit, so replan."""
    replan: bool = True
    max_replans: int = 10
    """Planner calls after the first one (repairs and replans)."""
    planner_timeout: float = 60.0
    """Hard limit of one planner call, in seconds."""
    planning_time_budget: float = 300.0
    """Total planning time of one execution, in seconds."""

    @classmethod
    def named(cls, name: str) -> ReplanPolicy:
        """Preset policies for ablations: full, no-replan, retry-only, replan-only."""
        presets = {
            "full": cls(),
            "repair-first": cls(),
            "no-replan": cls(
                max_step_retries=0, continue_if_valid=False, repair=False, replan=False
            ),
            "retry-only": cls(
                continue_if_valid=False, repair=False, replan=False, max_step_retries=3
            ),
            "replan-only": cls(max_step_retries=0, continue_if_valid=False, repair=False),
        }
        try:
            return presets[name]
        except KeyError:
            raise ValueError(
                f"unknown replanning policy {name!r}; policies: {', '.join(presets)}"
            ) from None


@dataclass
class ExecutionReport:
    """The numbers of one execution (``plan-bridge run --json`` prints them)."""

    outcome: str = ""
    goal_reached: bool = False
    actions_executed: int = 0
    actions_failed: int = 0
    retries: int = 0
    continues: int = 0
    repairs: int = 0
    repair_attempts: int = 0
    replans: int = 0
    planner_calls: int = 0
    planning_time_s: float = 0.0
    execution_time_s: float = 0.0
    total_time_s: float = 0.0
    final_plan: list[str] = field(default_factory=list)
    executed: list[str] = field(default_factory=list)
    decisions: list[dict[str, str]] = field(default_factory=list)
    explanation: str = ""

    def to_json(self) -> dict[str, Any]:
        data = dataclasses.asdict(self)
        for key in ("planning_time_s", "execution_time_s", "total_time_s"):
            data[key] = round(data[key], 4)
        return data


class _Stop(Exception):  # noqa: N818  (control flow, not an error)
    """Ends the mission with an outcome and an explanation (internal control flow)."""

    def __init__(self, outcome: str, explanation: str) -> None:
        super().__init__(explanation)
        self.outcome = outcome
        self.explanation = explanation


class Executive(smach.Container):
    """Plans for ``task`` and executes the plan with ``skills``, replanning on failure.

    Outcomes: ``succeeded`` (goal reached), ``aborted`` (no plan, budget exhausted,
    unrecoverable), ``preempted``. After a run, :attr:`report` holds the numbers.
    """

    def __init__(
        self,
        task: PlanningTask,
        skills: SkillRegistry,
        planner: Planner | str = "fast-downward",
        *,
        policy: ReplanPolicy | None = None,
        belief: WorldState | None = None,
        sense: Callable[[WorldState], Iterable[Any]] | None = None,
        concurrent: bool = False,
        check_preconditions: bool = True,
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        checkpoint: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        super().__init__(list(OUTCOMES), input_keys, output_keys)
        #: Called (from the step's thread) after every succeeded step with the state
        #: needed to resume: see :meth:`resume_from` and docs/reliability.md.
        self.checkpoint = checkpoint
        self._resume: dict[str, Any] | None = None
        self._checkpoint_lock = threading.Lock()
        self._plan_in_force: list[PlanStep] = []
        self._first_in_force = 1
        self._executed: list[tuple[int, str]] = []
        self.task = task
        self.skills = skills
        self.planner = get_planner(planner) if isinstance(planner, str) else planner
        self.policy = policy or ReplanPolicy()
        self.belief = belief if belief is not None else WorldState(task.initial_facts)
        self.sense = sense
        self.concurrent = concurrent
        self.check_preconditions = check_preconditions
        self.model = ActionModel(task)
        self.report = ExecutionReport()
        self._compiled: CompiledPlan | None = None
        self._running = False
        self._records: dict[int, StepRecord] = {}

    # -- Container interface ---------------------------------------------------------------
    def get_children(self) -> dict[str, smach.State]:
        return {"PLAN": self._compiled.machine} if self._compiled is not None else {}

    def get_initial_states(self) -> list[str]:
        return ["PLAN"] if self._compiled is not None else []

    def get_active_states(self) -> list[str]:
        return ["PLAN"] if self._running and self._compiled is not None else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        if self._compiled is None:
            return []
        edges: list[tuple[str, str, str | None]] = [(o, "PLAN", o) for o in OUTCOMES]
        return [*edges, ("aborted", "PLAN", "PLAN"), ("invalid", "PLAN", "PLAN")]

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: smach.UserData | None = None
    ) -> None:
        if userdata is not None:
            self.userdata.update(userdata)

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

    def is_running(self) -> bool:
        return self._running

    def request_preempt(self) -> None:
        super().request_preempt()
        compiled = self._compiled
        if self._running and compiled is not None:
            compiled.machine.request_preempt()

    # -- execution -------------------------------------------------------------------------
    def _run(self) -> str | None:
        """Run the mission; return succeeded / aborted / preempted.

        Called by ``smach.Container.execute``, the run protocol every container shares
        (input/output keys, started/terminated/error events, preempt bookkeeping).
        """
        started = time.monotonic()
        self.report = report = ExecutionReport()
        try:
            outcome = self._mission()
            report.explanation = report.explanation or "goal reached"
        except _Stop as stop:
            outcome, report.explanation = stop.outcome, stop.explanation
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
        self._sense()
        if self.model.goal_holds(self.belief.facts):
            self._decide("done", "the goal already holds")
            return "succeeded"
        if resume is None:
            plan = self._plan("initial plan", self.task)
        while True:
            self._check_preempt()
            first = self._next_label
            outcome, failed = self._run_plan(plan, first)
            self._next_label = max(self._records, default=first - 1) + 1
            if outcome == "preempted":
                self._decide("stop", "preempted")
                return "preempted"
            self._sense()
            if self.model.goal_holds(self.belief.facts):
                return "succeeded"
            if failed is None:
                reason = "the plan finished but the goal does not hold: " + ", ".join(
                    self.model.unmet_goals(self.belief.facts)
                )
                rest: list[PlanStep] = []
                record = None
            else:
                record = self._records.get(first + failed)
                reason = self._failure_reason(plan[failed], record)
                # The failed step first, then every other step not done yet (with
                # concurrent layers, later steps may be done and same-layer ones not).
                rest = [plan[failed]] + [
                    step
                    for i, step in enumerate(plan)
                    if i != failed and not self._succeeded(first + i)
                ]
            plan = self._recover(rest, reason, record)

    def _run_plan(self, plan: list[PlanStep], first_index: int) -> tuple[str, int | None]:
        """Run ``plan``; return (outcome, index in ``plan`` of the first unfinished step)."""
        compiled = compile_plan(
            plan,
            self.skills,
            self.model,
            self.belief,
            first_index=first_index,
            concurrent=self.concurrent,
            check_preconditions=self.check_preconditions,
            on_finished=self._step_finished,
        )
        self._compiled = compiled
        compiled.machine._parent = self
        compiled.machine._adopt(self._bus, f"{self._path}/PLAN")
        self._records = {}
        self._plan_in_force, self._first_in_force = plan, first_index
        self.report.final_plan = [str(s) for s in plan]
        if self._preempt_requested:
            compiled.machine.request_preempt()
        ud = smach.Remapper(
            self.userdata,
            compiled.machine.get_registered_input_keys(),
            compiled.machine.get_registered_output_keys(),
            owner=self,
            writer="PLAN",
        )
        outcome = compiled.machine.execute(ud)
        if outcome == "preempted" or self._preempt_requested:
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
        return {
            "plan": remaining,
            "first_index": max(done, default=first - 1) + 1,
            "belief": sorted(format_fact(f) for f in self.belief.facts),
            "report": self.report.to_json(),
            "userdata": _json_values(self.userdata),
        }

    def resume_from(self, snapshot: dict[str, Any]) -> None:
        """Make the next :meth:`execute` continue from a :meth:`snapshot` (no initial plan)."""
        for key in ("plan", "first_index", "belief", "report"):
            if key not in snapshot:
                raise ValueError(f"not an executive snapshot: the {key!r} entry is missing")
        self._resume = dict(snapshot)

    def _restore(self, snapshot: dict[str, Any]) -> tuple[list[PlanStep], int]:
        self.belief.replace(parse_fact(f) for f in snapshot["belief"])
        saved = snapshot["report"]
        report = self.report
        for name in (
            "actions_executed",
            "actions_failed",
            "retries",
            "continues",
            "repairs",
            "replans",
            "planner_calls",
            "planning_time_s",
        ):
            setattr(report, name, saved.get(name, 0))
        report.executed = list(saved.get("executed", []))
        self._executed = [
            (-len(report.executed) + i, step) for i, step in enumerate(report.executed)
        ]
        report.decisions = list(saved.get("decisions", []))
        for key, value in snapshot.get("userdata", {}).items():
            self.userdata[key] = value
        plan = [PlanStep(f[0], tuple(f[1:])) for f in (parse_fact(s) for s in snapshot["plan"])]
        self._decide("resume", f"resuming with {len(plan)} steps left from a checkpoint")
        return plan, int(snapshot["first_index"])

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

    # -- recovery ----------------------------------------------------------------------------
    def _recover(
        self, rest: list[PlanStep], reason: str, record: StepRecord | None
    ) -> list[PlanStep]:
        """Choose how to go on from a failure of ``rest[0]`` (or the end of the plan)."""
        policy = self.policy
        facts = self.belief.facts
        if rest:
            failed = rest[0]
            # Retries are counted per step of the plan in force (a new plan starts over).
            key = (self._generation, str(failed))
            tries = self._retry_counts.get(key, 0)
            ground = self.model.ground(failed)
            if (
                record is not None
                and record.outcome == "aborted"
                and tries < policy.max_step_retries
                and ground.applicable(facts)
            ):
                self._retry_counts[key] = tries + 1
                self.report.retries += 1
                self._decide("retry", f"{reason}; its preconditions still hold", str(failed))
                return rest
            if policy.continue_if_valid and len(rest) > 1:
                check = self.model.check_plan(rest[1:], facts)
                if check.valid:
                    self.report.continues += 1
                    self._decide(
                        "continue", f"{reason}; the rest of the plan is still valid", str(failed)
                    )
                    return rest[1:]
        if policy.repair and rest:
            repaired = self._repair(rest, reason)
            if repaired is not None:
                return repaired
        if policy.replan:
            self.report.replans += 1
            self._decide("replan", reason)
            self._generation += 1
            return self._plan(f"replan: {reason}", self.task)
        raise _Stop("aborted", f"{reason}; the policy allows no further recovery")

    def _repair(self, rest: list[PlanStep], reason: str) -> list[PlanStep] | None:
        """Plan a prefix that re-establishes what ``rest`` needs; None if that does not fit."""
        needed = self.model.regress(rest)
        if needed is None:
            return None
        facts = self.belief.facts
        missing = needed - facts
        if not missing:
            return None
        fixed = sorted(f for f in missing if f[0] not in self.model.addable_predicates())
        if fixed:
            # No action makes these true (they are observed, like a locked door): the
            # old plan cannot be rescued, and asking the planner would only cost time.
            self._decide("repair-skipped", f"no action can re-establish {_show(fixed)}")
            return None
        self.report.repair_attempts += 1
        # The goal atoms travel to the planner, which derives the repair problem from
        # the task it already parsed (no PDDL is written or parsed).
        prefix = self._plan(
            f"repair: re-establish {_show(missing)}", self.task, final=False, goal=needed
        )
        if prefix is None:
            return None
        candidate = [*prefix, *rest]
        limit = max(1, int(self.policy.repair_max_prefix_ratio * len(rest)))
        if not self.model.check_plan(candidate, facts).valid:
            why = "the repaired plan does not reach the goal"
        elif len(prefix) > limit:
            why = (
                f"the repair needs {len(prefix)} extra steps to rescue {len(rest)} "
                f"(more than {limit}): a new plan fits better"
            )
        else:
            self.report.repairs += 1
            self._budgeted_calls += 1
            self._generation += 1
            self._decide("repair", f"{reason}; {len(prefix)} steps re-establish {_show(missing)}")
            return candidate
        self._decide("repair-rejected", why)
        return None

    # -- planning ------------------------------------------------------------------------------
    def _plan(
        self,
        reason: str,
        task: PlanningTask,
        *,
        final: bool = True,
        goal: frozenset[Fact] | None = None,
    ) -> list[PlanStep]:
        """Plan from the belief; raise _Stop when the budget or the planner says no."""
        policy = self.policy
        report = self.report
        if final and self._budgeted_calls > policy.max_replans:
            raise _Stop(
                "aborted",
                f"replanning budget exhausted ({policy.max_replans} replans) after: {reason}",
            )
        remaining = policy.planning_time_budget - report.planning_time_s
        if remaining <= 0:
            raise _Stop(
                "aborted", f"planning time budget ({policy.planning_time_budget} s) exhausted"
            )
        timeout = min(policy.planner_timeout, remaining)
        result = self._solve(task, timeout, goal)
        report.planner_calls += 1
        if final:
            # Repair attempts are bounded by the failures and the time budget; only
            # plans that replace the plan in force use up the replanning budget.
            self._budgeted_calls += 1
        report.planning_time_s += result.planning_time_s
        if self._observed():
            t, thread = stamp()
            self._emit(
                PlanComputed(
                    path=self._path,
                    time=t,
                    thread=thread,
                    reason=reason,
                    planner=result.planner,
                    status=result.status.value,
                    steps=tuple(str(s) for s in result.actions),
                    planning_time_s=result.planning_time_s,
                    explanation=result.explanation,
                )
            )
        if not result.solved:
            if not final:
                return None  # type: ignore[return-value]
            raise _Stop("aborted", f"no plan ({result.status.value}): {result.explanation}")
        return list(result.actions)

    def _solve(
        self, task: PlanningTask, timeout: float, goal: frozenset[Fact] | None = None
    ) -> PlanResult:
        """Solve in a helper thread so that a preempt request is answered at once."""
        box: list[PlanResult | BaseException] = []
        done = threading.Event()
        facts = self.belief.facts

        def work() -> None:
            try:
                if goal is None:
                    box.append(self.planner.solve(task, timeout=timeout, initial_state=facts))
                else:
                    box.append(
                        self.planner.solve(task, timeout=timeout, initial_state=facts, goal=goal)
                    )
            except BaseException as exc:
                box.append(exc)
            finally:
                done.set()

        threading.Thread(target=work, name="plan-bridge-solve", daemon=True).start()
        event = self.preempt_event
        while not done.wait(0.05):
            if event.is_set():
                raise _Stop("preempted", "preempted while planning")
        value = box[0]
        if isinstance(value, BaseException):
            raise value
        return value

    # -- belief --------------------------------------------------------------------------------
    def _sense(self) -> None:
        if self.sense is None:
            return
        observations: list[Observation] = normalise_observations(self.sense(self.belief))
        self.belief.observe(observations)

    def _check_preempt(self) -> None:
        if self._preempt_requested:
            raise _Stop("preempted", "preempted")

    def _decide(self, decision: str, reason: str, step: str = "") -> None:
        self.report.decisions.append({"decision": decision, "reason": reason, "step": step})
        if self._observed():
            t, thread = stamp()
            self._emit(
                ExecutiveDecision(
                    path=self._path,
                    time=t,
                    thread=thread,
                    decision=decision,
                    reason=reason,
                    step=step,
                )
            )

    def _begin(self, parent_ud: smach.UserData | None) -> None:
        super()._begin(parent_ud)
        self._retry_counts: dict[tuple[int, str], int] = {}
        # Plans adopted so far (retries are counted per plan) and the next step label.
        self._generation = 0
        self._next_label = 1
        self._executed = []
        self._budgeted_calls = 0


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


def _show(facts: Iterable[Fact]) -> str:
    shown = sorted(format_fact(f) for f in facts)
    return ", ".join(shown[:6]) + (f" and {len(shown) - 6} more" if len(shown) > 6 else "")
