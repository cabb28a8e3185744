"""The recovery ladder: what the executive does after a step failed or the plan ended
without the goal.

The ladder is a list of :class:`RecoveryStrategy` objects that :class:`Recovery` walks
in order: each is asked for the plan to go on with, and the first that gives one wins
(a strategy may also end the mission by raising :class:`MissionEnded`, importable
from here); when none does, the mission ends ``aborted``. :func:`default_ladder` is,
in order, within the policy's budgets:

1. **continue** (:class:`ContinueIfValid`) with the rest of the plan if it is valid
   from the belief without the failed step (its effects came true anyway, e.g. a door
   somebody else opened);
2. **retry** (:class:`RetryStep`) the step while the held plan, that step included, is
   still valid from the belief (a fault that left the world as it was: no planner can
   do better than the plan in force), at most ``max_step_retries`` (3) times per step
   and plan; then run it with another **variant** of its skill
   (:class:`TrySkillVariant`), each variant once;
3. **repair** (sequential plans): first without a planner (:class:`RedoRecentSteps`),
   by re-doing the last executed steps (up to ``redo_window``) when that makes the
   held plan valid again (a failure that undid what they did: a block that slipped
   back); then (STRIPS-style plans, :class:`RepairPrefix`) regress the goal through
   the rest of the plan to the facts it needs, plan only a prefix that re-establishes
   the broken ones, and keep ``prefix + rest`` if it is valid and short;
4. **replan** (:class:`Replan`) from the belief (a reused plan for a state seen
   before, else the replan portfolio within the replan deadline). When that gives no
   plan while the held plan is still valid from the belief, **hold**: go on with the
   held plan instead of aborting (the planner's time-out says nothing against a plan
   that still works).

Every plan adopted after the first one (a redo, a planned repair, a replan) counts
against ``max_replans``: a failure that keeps coming back ends the mission instead
of looping. Retries start afresh with each adopted plan, so they are bounded too.
A temporal plan is never re-done: its steps' times and overlaps would be lost (the
hold-door must overlap the pass-door), so it goes to the planner.

A user's own strategy is any object with a ``name`` and an ``attempt(failure,
ladder)`` method (:class:`RecoveryStrategy`); it goes into the list given to the
executive (``Executive(..., recovery_ladder=[MyStrategy(), *default_ladder()])``, or
``executive.recovery_ladder``). It reads the failure (:class:`Failure`) and uses the
ladder's model, belief, budgets and report, and tells why it chose what it chose with
``ladder.decide``. A strategy object lives as long as the executive that holds it
(its executions share it); what one execution counts for the built-in rungs (retries,
variants tried, plans adopted) lives on the :class:`Recovery` of that execution.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from plan_bridge.belief import Belief
from plan_bridge.execution.policy import ExecutionReport, ReplanPolicy
from plan_bridge.execution.replanner import MissionEnded, Replanner
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.steps import StepRecord
from plan_bridge.execution.temporal_network import is_temporal
from plan_bridge.pddl.task import Fact, format_fact, parse_fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = [
    "ContinueIfValid",
    "Failure",
    "MissionEnded",
    "Recovery",
    "RecoveryStrategy",
    "RedoRecentSteps",
    "RepairPrefix",
    "Replan",
    "RetryStep",
    "TrySkillVariant",
    "default_ladder",
]

Decide = Callable[[str, str, str], None]


@dataclass(frozen=True)
class Failure:
    """What the ladder recovers from."""

    rest: list[PlanStep]
    """The failed step first, then every other step not done yet; empty when the plan
    ended without the goal."""
    reason: str
    """Why the plan stopped, as the decisions and the report say it."""
    record: StepRecord | None
    """What happened to the failed step (None: it did not run, or the plan ended)."""
    facts: frozenset[Fact]
    """The belief when the ladder began."""
    held_valid: bool
    """Whether ``rest``, the failed step included, is valid from ``facts``."""

    @property
    def aborted(self) -> bool:
        """Whether the failed step ran and its skill ended ``aborted``."""
        return self.record is not None and self.record.outcome == "aborted"


@runtime_checkable
class RecoveryStrategy(Protocol):
    """One rung of the recovery ladder."""

    name: str
    """What the strategy is called in the documentation and in messages."""

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        """The plan to go on with (counted and told with ``ladder.decide``), or None to
        let the next rung try; raises :class:`MissionEnded` to end the mission."""
        ...


class ContinueIfValid:
    """Skip the failed step when the rest of the plan is valid without it."""

    name = "continue"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        rest = failure.rest
        if not (ladder.policy.continue_if_valid and len(rest) > 1):
            return None
        if not ladder.model.check_plan(rest[1:], failure.facts).valid:
            return None
        ladder.report.continues += 1
        ladder.decide(
            "continue", f"{failure.reason}; the rest of the plan is still valid", str(rest[0])
        )
        return rest[1:]


class RetryStep:
    """Run the aborted step again while the held plan is valid (``max_step_retries``
    per step and plan)."""

    name = "retry"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        if not failure.rest:
            return None
        key = (ladder.generation, str(failure.rest[0]))
        tries = ladder.retry_counts.get(key, 0)
        if not (failure.aborted and tries < ladder.policy.max_step_retries and failure.held_valid):
            return None
        ladder.retry_counts[key] = tries + 1
        ladder.report.retries += 1
        ladder.decide(
            "retry",
            f"{failure.reason}; the plan, this step included, is still valid",
            str(failure.rest[0]),
        )
        return failure.rest


class TrySkillVariant:
    """Run the aborted step with another variant of its skill, each variant once."""

    name = "variant"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        if not (failure.rest and failure.held_valid and ladder.policy.try_variants):
            return None
        failed = failure.rest[0]
        variant = ladder.next_variant(failed)  # (tried, even when it is not run now)
        if variant is None or not failure.aborted:
            return None
        ladder.variant_for[str(failed)] = variant
        ladder.report.variants_tried += 1
        ladder.decide(
            "variant",
            f"{failure.reason}; the plan is still valid: trying the skill variant {variant!r}",
            str(failed),
        )
        return failure.rest


class RedoRecentSteps:
    """Re-do the last executed steps (up to ``redo_window``) when that makes the held
    sequential plan valid again: no planner call."""

    name = "redo"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        rest, policy = failure.rest, ladder.policy
        if not (rest and ladder.may_repair() and policy.redo_window):
            return None
        if failure.held_valid or is_temporal(rest):
            return None
        history = ladder.report.executed[-policy.redo_window :]
        done = [PlanStep(f[0], tuple(f[1:])) for f in (parse_fact(s) for s in history)]
        for count in range(1, min(len(done), ladder.prefix_limit(rest)) + 1):
            prefix = done[-count:]
            if ladder.model.check_plan([*prefix, *rest], failure.facts).valid:
                ladder.adopt_repair(
                    f"{failure.reason}; re-doing {', '.join(str(s) for s in prefix)} makes "
                    "the plan valid again (no planner call)"
                )
                return [*prefix, *rest]
        return None


class RepairPrefix:
    """Plan a short prefix that re-establishes what the rest of the plan needs
    (STRIPS-style plans: the goal regressed through the rest)."""

    name = "repair"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        rest = failure.rest
        if not (rest and ladder.may_repair()):
            return None
        model = ladder.model
        needed = model.regress(rest)
        if needed is None:
            return None
        facts = ladder.belief.facts
        missing = needed - facts
        if not missing:
            return None
        fixed = sorted(f for f in missing if f[0] not in model.addable_predicates())
        if fixed:
            # No action makes these true (they are observed, like a locked door): the
            # old plan cannot be rescued, and asking the planner would only cost time.
            ladder.decide("repair-skipped", f"no action can re-establish {show(fixed)}", "")
            return None
        ladder.report.repair_attempts += 1
        # The goal atoms travel to the planner, which derives the repair problem from
        # the task it already parsed (no PDDL is written or parsed).
        result = ladder.replanner.plan(
            f"repair: re-establish {show(missing)}", final=False, goal=needed
        )
        if not result.solved:
            return None
        prefix = list(result.actions)
        candidate = [*prefix, *rest]
        limit = ladder.prefix_limit(rest)
        if not model.check_plan(candidate, facts).valid:
            why = "the repaired plan does not reach the goal"
        elif len(prefix) > limit:
            why = (
                f"the repair needs {len(prefix)} extra steps to rescue {len(rest)} "
                f"(more than {limit}): a new plan fits better"
            )
        else:
            ladder.adopt_repair(
                f"{failure.reason}; {len(prefix)} steps re-establish {show(missing)}"
            )
            return candidate
        ladder.decide("repair-rejected", why, "")
        return None


class Replan:
    """Plan from the belief; when that gives no plan while the held plan is still
    valid, hold it (``hold_valid_plan``), else end the mission."""

    name = "replan"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        policy, report, rest = ladder.policy, ladder.report, failure.rest
        if not policy.replan:
            return None
        ladder.decide("replan", failure.reason, "")
        result = ladder.replanner.plan(f"replan: {failure.reason}", replan=True)
        report.replans += 1  # counted once the budget allowed it
        ladder.generation += 1
        if result.solved:
            return list(result.actions)
        no_plan = f"no plan ({result.status.value}): {result.explanation}"
        if (
            policy.hold_valid_plan
            and failure.held_valid
            and ladder.model.check_plan(rest, ladder.belief.facts).valid
        ):
            report.holds += 1
            ladder.decide(
                "hold",
                f"{no_plan}; the held plan ({len(rest)} steps) is still valid from the "
                "belief: going on with it",
                str(rest[0]),
            )
            return rest
        raise MissionEnded("aborted", no_plan)


def default_ladder() -> list[RecoveryStrategy]:
    """The ladder of the module documentation, a new list each time (to add to)."""
    return [
        ContinueIfValid(),
        RetryStep(),
        TrySkillVariant(),
        RedoRecentSteps(),
        RepairPrefix(),
        Replan(),
    ]


class Recovery:
    """Walks the recovery ladder after a failure (one instance per execution): what
    the strategies share, and what one execution counts."""

    def __init__(
        self,
        model: ActionModel,
        policy: ReplanPolicy,
        belief: Belief,
        replanner: Replanner,
        report: ExecutionReport,
        decide: Decide,
        skills: SkillRegistry | None = None,
        ladder: Sequence[RecoveryStrategy] | None = None,
    ) -> None:
        self.skills = skills
        self.model = model
        self.policy = policy
        self.belief = belief
        self.replanner = replanner
        self.report = report
        self.decide = decide
        self.ladder: list[RecoveryStrategy] = default_ladder() if ladder is None else list(ladder)
        #: Plans adopted so far: retries are counted per step of the plan in force.
        self.generation = 0
        #: Retries so far, per (generation, step).
        self.retry_counts: dict[tuple[int, str], int] = {}
        #: The skill variant each ground step runs with from now on (by ``str(step)``).
        self.variant_for: dict[str, str] = {}
        self._variants_tried: dict[str, list[str]] = {}

    def recover(
        self, rest: list[PlanStep], reason: str, record: StepRecord | None
    ) -> list[PlanStep]:
        """The plan to go on with after a failure of ``rest[0]`` (or the end of the
        plan, when ``rest`` is empty); raises :class:`MissionEnded` to stop."""
        facts = self.belief.facts
        held_valid = bool(rest) and self.model.check_plan(rest, facts).valid
        failure = Failure(rest, reason, record, facts, held_valid)
        for strategy in self.ladder:
            plan = strategy.attempt(failure, self)
            if plan is not None:
                return plan
        raise MissionEnded("aborted", f"{reason}; the policy allows no further recovery")

    def variants_of(self, plan: list[PlanStep]) -> dict[int, str]:
        """Position in ``plan`` -> the skill variant that step runs with."""
        chosen = self.variant_for
        if not chosen:
            return {}
        return {i: chosen[str(s)] for i, s in enumerate(plan) if str(s) in chosen}

    def next_variant(self, step: PlanStep) -> str | None:
        """A variant of ``step``'s skill not tried yet in this execution (marked tried)."""
        if self.skills is None:
            return None
        tried = self._variants_tried.setdefault(str(step), [])
        for name in self.skills.variants(step.action):
            if name not in tried:
                tried.append(name)
                return name
        return None

    def may_repair(self) -> bool:
        """Whether the policy repairs and the budget allows one more adopted plan (else
        the replan ends the mission with the budget's message)."""
        return self.policy.repair and self.replanner.budgeted_calls <= self.policy.max_replans

    def prefix_limit(self, rest: Sequence[PlanStep]) -> int:
        """The longest prefix a repair may put before ``rest``."""
        return max(1, int(self.policy.repair_max_prefix_ratio * len(rest)))

    def adopt_repair(self, why: str) -> None:
        """Count a repaired plan against the budget (it can fail again) and tell why."""
        self.report.repairs += 1
        self.replanner.budgeted_calls += 1
        self.generation += 1
        self.decide("repair", why, "")


def show(facts: Iterable[Fact]) -> str:
    """Facts as PDDL text, at most six of them."""
    shown = sorted(format_fact(f) for f in facts)
    return ", ".join(shown[:6]) + (f" and {len(shown) - 6} more" if len(shown) > 6 else "")
