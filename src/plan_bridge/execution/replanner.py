"""Where the executive's plans come from: the planner calls of one execution.

A :class:`Replanner` asks the planner for the initial plan and for repairs and
replans, within the policy's budgets (planner calls, planning time, a replan's own
deadline). Before calling a planner it looks up the plan found before for the same
(state, goal) in a :class:`~plan_bridge.execution.plan_cache.PlanCache`. A replan goes
to a portfolio of Fast Downward configurations (:mod:`plan_bridge.planning.portfolio`)
when the executive's planner is Fast Downward; ``auto`` plans with the warm search
first (:meth:`~plan_bridge.planning.engines.AutoPlanner.for_execution`), and a plan of
the warm search that the action model does not accept is planned again by the
engines. Every solve runs in a helper thread, so that a preempt request is answered
at once (and kills the planner process).
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Sequence

from plan_bridge.belief import Belief, FactSnapshot
from plan_bridge.execution.plan_cache import PlanCache
from plan_bridge.execution.policy import ExecutionReport, ReplanPolicy
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.task_view import project
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.planning.engines import WARM, AutoPlanner
from plan_bridge.planning.planner import UPPlanner
from plan_bridge.planning.portfolio import fast_downward_portfolio
from plan_bridge.planning.types import Planner, PlanResult, PlanStatus, PlanStep, accepts_cancel

__all__ = ["MissionEnded", "Replanner"]


class MissionEnded(Exception):  # noqa: N818  (control flow, not an error)
    """Ends the mission with an outcome and an explanation (internal control flow)."""

    def __init__(self, outcome: str, explanation: str) -> None:
        super().__init__(explanation)
        self.outcome = outcome
        self.explanation = explanation


class Replanner:
    """The planner calls of one execution (see the module docstring)."""

    def __init__(
        self,
        task: PlanningTask,
        planner: Planner,
        policy: ReplanPolicy,
        model: ActionModel,
        belief: Belief,
        cache: PlanCache,
        preempt: threading.Event,
        on_plan: Callable[[str, PlanResult], None],
        *,
        projected: bool = False,
    ) -> None:
        self.task = task
        #: Give the planner only the belief's facts about the task's objects (the
        #: belief of a task view holds the whole world's: execution/task_view.py).
        self.projected = projected
        self.planner = planner
        # What plans: ``auto`` with the warm search first (replans start no process).
        self._solver = planner.for_execution() if isinstance(planner, AutoPlanner) else planner
        self.policy = policy
        self.model = model
        self.belief = belief
        self.cache = cache
        self.preempt = preempt
        self.on_plan = on_plan
        self.report = ExecutionReport()
        #: Plans that replaced the plan in force, after the first one.
        self.budgeted_calls = 0
        #: Narrows what the planner is told of the belief (an order mission leaves out
        #: a robot it benched); None: the belief (projected) as it is.
        self.restrict: Callable[[FactSnapshot], FactSnapshot] | None = None
        self._window_start_s = 0.0
        self._replan_planner: Planner | None = None
        # Replans of this execution that gave no plan, by (state, goal): asking again
        # from the same state would only wait for the same time-out.
        self._no_plan: dict[tuple[frozenset[Fact], frozenset[Fact] | None], PlanResult] = {}

    @property
    def replan_planner(self) -> Planner:
        """The planner of replans: the portfolio, built on the first replan."""
        if self._replan_planner is None:
            self._replan_planner = self._build_replan_planner()
        return self._replan_planner

    def _build_replan_planner(self) -> Planner:
        planner = self._solver
        names = self.policy.replan_portfolio
        if names and isinstance(planner, UPPlanner) and planner.engine == "fast-downward":
            portfolio = fast_downward_portfolio(names, pool=planner.pool, first=planner)
            if len(portfolio.members) > 1:
                return portfolio
        return planner

    def _engine_planner(self) -> Planner:
        """The planner without the warm search (``auto``'s engines, else Fast Downward)."""
        if isinstance(self.planner, AutoPlanner) and not self.planner.warm:
            return self.planner
        pool = self.planner.pool if isinstance(self.planner, UPPlanner) else None
        return UPPlanner(pool=pool)

    def start(self, report: ExecutionReport) -> None:
        """Begin an execution that reports into ``report``."""
        self.report = report
        self.new_window()

    def new_window(self) -> None:
        """Give the budgets (replans, planning time) afresh from now, and forget which
        states gave no plan: a mission of many goals (orders) budgets each goal's
        plans, not the whole run's."""
        self.budgeted_calls = 0
        self._no_plan = {}
        self._window_start_s = self.report.planning_time_s

    def plan(
        self,
        reason: str,
        *,
        final: bool = True,
        replan: bool = False,
        goal: frozenset[Fact] | None = None,
    ) -> PlanResult:
        """A plan from the belief (``goal``: these atoms instead of the task's goal).

        ``final`` plans replace the plan in force and use up the replanning budget;
        ``replan`` ones get the policy's replan deadline and portfolio. Raises
        :class:`MissionEnded` when a budget is exhausted or a preempt arrives; "no plan"
        is a result, for the caller to decide on.
        """
        policy, report = self.policy, self.report
        if final and self.budgeted_calls > policy.max_replans:
            raise MissionEnded(
                "aborted",
                f"replanning budget exhausted ({policy.max_replans} replans) after: {reason}",
            )
        facts = project(self.belief.facts, self.task) if self.projected else self.belief.facts
        if self.restrict is not None:
            facts = self.restrict(facts)
        if policy.reuse_plans:
            reused = self._reuse(facts, goal)
            if reused is not None:
                report.plans_reused += 1
                if final:
                    self.budgeted_calls += 1
                self.on_plan(f"{reason} (plan reused: same state and goal)", reused)
                return reused
        known = self._no_plan.get((facts, goal)) if replan else None
        if known is not None:
            if final:
                self.budgeted_calls += 1
            result = dataclasses.replace(
                known,
                planning_time_s=0.0,
                explanation=f"{known.explanation} (an earlier replan from this state)",
            )
            self.on_plan(f"{reason} (no plan from this state before)", result)
            return result
        remaining = policy.planning_time_budget - (report.planning_time_s - self._window_start_s)
        if remaining <= 0:
            raise MissionEnded(
                "aborted", f"planning time budget ({policy.planning_time_budget} s) exhausted"
            )
        timeout = min(policy.planner_timeout, remaining)
        planner = self._solver
        if replan:
            timeout = min(timeout, policy.replan_timeout)
            planner = self.replan_planner
        result = self._solve(planner, facts, timeout, goal)
        if (
            result.solved
            and result.planner == WARM
            and not self._reaches(result.actions, facts, goal)
        ):
            # The warm search's plan does not fit the action model: an engine plans.
            result = self._solve(self._engine_planner(), facts, timeout, goal)
        report.planner_calls += 1
        if final:
            self.budgeted_calls += 1
        report.planning_time_s += result.planning_time_s
        if replan and not result.solved and not self.preempt.is_set():
            self._no_plan[(facts, goal)] = result
        if result.solved:
            report.planners_won[result.planner] = report.planners_won.get(result.planner, 0) + 1
            if policy.reuse_plans:
                self.cache.put(self.task, facts, goal, result.actions, result.planner)
        self.on_plan(reason, result)
        return result

    def _reuse(self, facts: frozenset[Fact], goal: frozenset[Fact] | None) -> PlanResult | None:
        hit = self.cache.get(self.task, facts, goal)
        if hit is None:
            return None
        steps, planner = hit
        if not self._reaches(steps, facts, goal):
            return None  # defensive: a plan that does not fit is planned afresh
        return PlanResult(PlanStatus.SOLVED, steps, planner=planner)

    def _reaches(
        self, steps: Sequence[PlanStep], facts: frozenset[Fact], goal: frozenset[Fact] | None
    ) -> bool:
        if goal is None:
            return self.model.check_plan(steps, facts).valid
        state = set(facts)
        for step in steps:
            ground = self.model.ground(step)
            if not ground.applicable(state):
                return False
            adds, dels = ground.effects(state)
            state -= dels
            state |= adds
        return goal <= state

    def _solve(
        self,
        planner: Planner,
        facts: frozenset[Fact],
        timeout: float,
        goal: frozenset[Fact] | None,
    ) -> PlanResult:
        """Solve in a helper thread so that a preempt request is answered at once."""
        box: list[PlanResult | BaseException] = []
        done = threading.Event()
        task, cancel = self.task, self.preempt

        def work() -> None:
            try:
                if accepts_cancel(planner):
                    # The preempt event cancels the solve: its process is killed.
                    box.append(
                        planner.solve(
                            task, timeout=timeout, initial_state=facts, goal=goal, cancel=cancel
                        )
                    )
                elif goal is None:
                    box.append(planner.solve(task, timeout=timeout, initial_state=facts))
                else:
                    box.append(planner.solve(task, timeout=timeout, initial_state=facts, goal=goal))
            except BaseException as exc:
                box.append(exc)
            finally:
                done.set()

        threading.Thread(target=work, name="plan-bridge-solve", daemon=True).start()
        while not done.wait(0.05):
            if cancel.is_set():
                raise MissionEnded("preempted", "preempted while planning")
        if cancel.is_set():
            raise MissionEnded("preempted", "preempted while planning")
        value = box[0]
        if isinstance(value, BaseException):
            raise value
        return value
