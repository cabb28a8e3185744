"""The recovery ladder: what the executive does after a step failed or the plan ended
without the goal.

In order, within the policy's budgets:

1. **continue** with the rest of the plan if it is valid from the belief without the
   failed step (its effects came true anyway, e.g. a door somebody else opened);
2. **retry** the step while the held plan, that step included, is still valid from
   the belief (a fault that left the world as it was: no planner can do better than
   the plan in force), at most ``max_step_retries`` (3) times per step and plan; then
   run it with another **variant** of its skill, each variant once;
3. **repair** (sequential plans): first without a planner, by re-doing the last
   executed steps (up to ``redo_window``) when that makes the held plan valid again
   (a failure that undid what they did: a block that slipped back); then
   (STRIPS-style plans) regress the goal through the rest of the plan to the facts it needs, plan only a
   prefix that re-establishes the broken ones, and keep ``prefix + rest`` if it is
   valid and short;
4. **replan** from the belief (a reused plan for a state seen before, else the replan
   portfolio within the replan deadline). When that gives no plan while the held
   plan is still valid from the belief, **hold**: go on with the held plan instead of
   aborting (the planner's time-out says nothing against a plan that still works).

Every plan adopted after the first one (a redo, a planned repair, a replan) counts
against ``max_replans``: a failure that keeps coming back ends the mission instead
of looping. Retries start afresh with each adopted plan, so they are bounded too.
A temporal plan is never re-done: its steps' times and overlaps would be lost (the
hold-door must overlap the pass-door), so it goes to the planner.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from plan_bridge.execution.compile import StepRecord
from plan_bridge.execution.policy import ExecutionReport, ReplanPolicy
from plan_bridge.execution.replanner import MissionEnded, Replanner
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.temporal import is_temporal
from plan_bridge.execution.world import WorldState
from plan_bridge.pddl.task import Fact, format_fact, parse_fact
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = ["Recovery"]

Decide = Callable[[str, str, str], None]


class Recovery:
    """Chooses how to go on after a failure (one instance per execution)."""

    def __init__(
        self,
        model: ActionModel,
        policy: ReplanPolicy,
        belief: WorldState,
        replanner: Replanner,
        report: ExecutionReport,
        decide: Decide,
        skills: SkillRegistry | None = None,
    ) -> None:
        self.skills = skills
        self.model = model
        self.policy = policy
        self.belief = belief
        self.replanner = replanner
        self.report = report
        self.decide = decide
        #: Plans adopted so far: retries are counted per step of the plan in force.
        self.generation = 0
        self._retry_counts: dict[tuple[int, str], int] = {}
        #: The skill variant each ground step runs with from now on (by ``str(step)``).
        self.variant_for: dict[str, str] = {}
        self._variants_tried: dict[str, list[str]] = {}

    def recover(
        self, rest: list[PlanStep], reason: str, record: StepRecord | None
    ) -> list[PlanStep]:
        """The plan to go on with after a failure of ``rest[0]`` (or the end of the
        plan, when ``rest`` is empty); raises :class:`MissionEnded` to stop."""
        policy, report = self.policy, self.report
        facts = self.belief.facts
        held_valid = bool(rest) and self.model.check_plan(rest, facts).valid
        if rest:
            failed = rest[0]
            if (
                policy.continue_if_valid
                and len(rest) > 1
                and self.model.check_plan(rest[1:], facts).valid
            ):
                report.continues += 1
                self.decide(
                    "continue", f"{reason}; the rest of the plan is still valid", str(failed)
                )
                return rest[1:]
            key = (self.generation, str(failed))
            tries = self._retry_counts.get(key, 0)
            if (
                record is not None
                and record.outcome == "aborted"
                and tries < policy.max_step_retries
                and held_valid
            ):
                self._retry_counts[key] = tries + 1
                report.retries += 1
                self.decide(
                    "retry", f"{reason}; the plan, this step included, is still valid", str(failed)
                )
                return rest
            variant = self._next_variant(failed) if held_valid and policy.try_variants else None
            if variant is not None and record is not None and record.outcome == "aborted":
                self.variant_for[str(failed)] = variant
                report.variants_tried += 1
                self.decide(
                    "variant",
                    f"{reason}; the plan is still valid: trying the skill variant {variant!r}",
                    str(failed),
                )
                return rest
            # Within budget: the next adopted plan may be a repair (else the replan
            # below ends the mission with the budget's message).
            repair = policy.repair and self.replanner.budgeted_calls <= policy.max_replans
            if repair and policy.redo_window and not held_valid and not is_temporal(rest):
                redone = self._redo(rest, reason, facts)
                if redone is not None:
                    return redone
            if repair:
                repaired = self._repair(rest, reason)
                if repaired is not None:
                    return repaired
        if not policy.replan:
            raise MissionEnded("aborted", f"{reason}; the policy allows no further recovery")
        self.decide("replan", reason, "")
        result = self.replanner.plan(f"replan: {reason}", replan=True)
        report.replans += 1  # counted once the budget allowed it
        self.generation += 1
        if result.solved:
            return list(result.actions)
        no_plan = f"no plan ({result.status.value}): {result.explanation}"
        if (
            policy.hold_valid_plan
            and held_valid
            and self.model.check_plan(rest, self.belief.facts).valid
        ):
            report.holds += 1
            self.decide(
                "hold",
                f"{no_plan}; the held plan ({len(rest)} steps) is still valid from the belief: "
                "going on with it",
                str(rest[0]),
            )
            return rest
        raise MissionEnded("aborted", no_plan)

    def variants_of(self, plan: list[PlanStep]) -> dict[int, str]:
        """Position in ``plan`` -> the skill variant that step runs with."""
        chosen = self.variant_for
        if not chosen:
            return {}
        return {i: chosen[str(s)] for i, s in enumerate(plan) if str(s) in chosen}

    def _next_variant(self, step: PlanStep) -> str | None:
        if self.skills is None:
            return None
        tried = self._variants_tried.setdefault(str(step), [])
        for name in self.skills.variants(step.action):
            if name not in tried:
                tried.append(name)
                return name
        return None

    def _redo(
        self, rest: list[PlanStep], reason: str, facts: frozenset[Fact]
    ) -> list[PlanStep] | None:
        """Re-do the last executed steps if that makes ``rest`` valid again."""
        history = self.report.executed[-self.policy.redo_window :]
        if not history:
            return None
        done = [PlanStep(f[0], tuple(f[1:])) for f in (parse_fact(s) for s in history)]
        limit = max(1, int(self.policy.repair_max_prefix_ratio * len(rest)))
        for count in range(1, min(len(done), limit) + 1):
            prefix = done[-count:]
            if self.model.check_plan([*prefix, *rest], facts).valid:
                self.report.repairs += 1
                self.replanner.budgeted_calls += 1  # a redo can fail again: bounded
                self.generation += 1
                self.decide(
                    "repair",
                    f"{reason}; re-doing {', '.join(str(s) for s in prefix)} makes the plan "
                    "valid again (no planner call)",
                    "",
                )
                return [*prefix, *rest]
        return None

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
            self.decide("repair-skipped", f"no action can re-establish {show(fixed)}", "")
            return None
        self.report.repair_attempts += 1
        # The goal atoms travel to the planner, which derives the repair problem from
        # the task it already parsed (no PDDL is written or parsed).
        result = self.replanner.plan(
            f"repair: re-establish {show(missing)}", final=False, goal=needed
        )
        if not result.solved:
            return None
        prefix = list(result.actions)
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
            self.replanner.budgeted_calls += 1
            self.generation += 1
            self.decide("repair", f"{reason}; {len(prefix)} steps re-establish {show(missing)}", "")
            return candidate
        self.decide("repair-rejected", why, "")
        return None


def show(facts: Iterable[Fact]) -> str:
    """Facts as PDDL text, at most six of them."""
    shown = sorted(format_fact(f) for f in facts)
    return ", ".join(shown[:6]) + (f" and {len(shown) - 6} more" if len(shown) > 6 else "")
