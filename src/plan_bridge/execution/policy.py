"""How the executive recovers from failures (:class:`ReplanPolicy`) and what one
execution reports (:class:`ExecutionReport`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

__all__ = ["ExecutionReport", "ReplanPolicy"]


@dataclass(frozen=True)
class ReplanPolicy:
    """How the executive recovers from failures, and its budgets."""

    max_step_retries: int = 3
    """Retries of one failed step while the held plan (that step included) is still
    valid from the belief: a fault that left the world as it was. A planner asked
    from such a state has the problem the held plan already solves, so retrying is
    cheaper than replanning (benchmarks/plan_bridge_recovery.py: with faults at 0.2
    on blocks probBLOCKS-14-0, 3 retries cut the replans per mission from 1.1 to 0.2)."""
    try_variants: bool = True
    """Then switch to another variant of the step's skill (``SkillRegistry.register(...,
    variant=...)``) while the held plan is still valid, each variant once."""
    continue_if_valid: bool = True
    """Skip ahead when the rest of the plan is valid from the belief."""
    repair: bool = True
    """Try a repair prefix before a full replan (STRIPS-style plans only)."""
    redo_window: int = 3
    """A repair first tries, without a planner, to re-do up to this many of the last
    executed steps (a failure that undid them); 0: never."""
    repair_max_prefix_ratio: float = 0.5
    """Keep a repaired plan only if its new prefix is at most this fraction of the
    plan it rescues: a long detour means the old plan is a poor fit, so replan."""
    replan: bool = True
    max_replans: int = 10
    """Plans adopted after the first one (redos, repairs, replans): the bound that
    keeps a failure that comes back from looping."""
    planner_timeout: float = 60.0
    """Hard limit of one planner call, in seconds."""
    replan_timeout: float = 20.0
    """Deadline of one replan (all configurations of the replan portfolio within it),
    at most ``planner_timeout``."""
    replan_portfolio: tuple[str, ...] = ("add-wastar", "cg-eager")
    """Fast Downward configurations (names in
    :data:`plan_bridge.planning.portfolio.FAST_DOWNWARD_CONFIGS`) a replan tries
    besides the executive's own planner, when that is Fast Downward: a greedy search
    can lose itself from a state where another configuration does not. Empty: the
    planner alone."""
    hold_valid_plan: bool = True
    """When a replan gives no plan (timeout, error) but the held plan is still valid
    from the belief, go on with the held plan instead of aborting."""
    reuse_plans: bool = True
    """Reuse the plan found before for an identical (state, goal) pair."""
    planning_time_budget: float = 300.0
    """Total planning time of one execution, in seconds."""

    def __post_init__(self) -> None:
        for name in ("max_step_retries", "max_replans", "redo_window"):
            if getattr(self, name) < 0:
                raise ValueError(f"ReplanPolicy.{name} must be >= 0, got {getattr(self, name)}")
        for name in ("planner_timeout", "replan_timeout", "planning_time_budget"):
            if not getattr(self, name) > 0:
                raise ValueError(f"ReplanPolicy.{name} must be > 0, got {getattr(self, name)}")
        from plan_bridge.planning.portfolio import FAST_DOWNWARD_CONFIGS

        unknown = [n for n in self.replan_portfolio if n not in FAST_DOWNWARD_CONFIGS]
        if unknown:
            raise ValueError(
                f"ReplanPolicy.replan_portfolio: unknown configuration(s) {', '.join(unknown)}; "
                f"configurations: {', '.join(FAST_DOWNWARD_CONFIGS)}"
            )

    @classmethod
    def named(cls, name: str) -> ReplanPolicy:
        """Preset policies for ablations: full, no-replan, retry-only, replan-only
        (every failure goes to the planner: no retry, continue, repair, plan reuse,
        held plan or portfolio)."""
        presets = {
            "full": cls(),
            "repair-first": cls(),
            "no-replan": cls(
                max_step_retries=0,
                try_variants=False,
                continue_if_valid=False,
                repair=False,
                replan=False,
            ),
            "retry-only": cls(
                continue_if_valid=False,
                try_variants=False,
                repair=False,
                replan=False,
                max_step_retries=3,
            ),
            "replan-only": cls(
                max_step_retries=0,
                try_variants=False,
                continue_if_valid=False,
                repair=False,
                hold_valid_plan=False,
                reuse_plans=False,
                replan_portfolio=(),
            ),
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
    variants_tried: int = 0
    """Failed steps run again with another variant of their skill."""
    continues: int = 0
    repairs: int = 0
    repair_attempts: int = 0
    replans: int = 0
    planner_calls: int = 0
    """Calls that reached a planner (a reused plan is not one)."""
    plans_reused: int = 0
    """Plans taken from the plan cache for an identical (state, goal) pair."""
    holds: int = 0
    """Replans that gave no plan, after which the still valid held plan went on."""
    planners_won: dict[str, int] = field(default_factory=dict)
    """Which planner (configuration) found each plan of this execution."""
    planning_time_s: float = 0.0
    execution_time_s: float = 0.0
    total_time_s: float = 0.0
    final_plan: list[str] = field(default_factory=list)
    executed: list[str] = field(default_factory=list)
    decisions: list[dict[str, str]] = field(default_factory=list)
    explanation: str = ""
    orders: dict[str, Any] = field(default_factory=dict)
    """A mission of orders: counts by status, latency, throughput (empty otherwise)."""

    def to_json(self) -> dict[str, Any]:
        data = dataclasses.asdict(self)
        if not self.orders:
            del data["orders"]
        for key in ("planning_time_s", "execution_time_s", "total_time_s"):
            data[key] = round(data[key], 4)
        return data
