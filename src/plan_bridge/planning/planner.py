"""Where most modules import the planning names from: a front that only re-exports.

>>> task = load_task("domain.pddl", "problem.pddl")          # doctest: +SKIP
>>> result = get_planner("fast-downward").solve(task, timeout=10)  # doctest: +SKIP
>>> [str(step) for step in result.actions]                  # doctest: +SKIP
['(pick ball1 rooma left)', ...]

The result types live in :mod:`.types`, the planners by name in :mod:`.registry`,
:class:`UPPlanner` (a unified-planning engine in a killable worker) in
:mod:`.up_planner` and engine choice in :mod:`.engines`. None of those imports this
module, so importing it closes no circle.
"""

from __future__ import annotations

from plan_bridge.planning.registry import get_planner
from plan_bridge.planning.types import Planner, PlanResult, PlanStatus, PlanStep
from plan_bridge.planning.up_planner import (
    DEFAULT_PLANNER,
    SolveRequest,
    UPPlanner,
    installed_planners,
    up_kind,
)

__all__ = [
    "DEFAULT_PLANNER",
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "SolveRequest",
    "UPPlanner",
    "get_planner",
    "installed_planners",
    "up_kind",
]
