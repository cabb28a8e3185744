"""Stage 2, planning: planners (unified-planning engines), the worker process that runs
them under a hard time limit, and plans (:class:`PlanResult`, :class:`PlanStep`).

``from plan_bridge.planning import get_planner`` is the public entry; the modules are
:mod:`~plan_bridge.planning.planner` and :mod:`~plan_bridge.planning.worker`.
"""

from __future__ import annotations

from plan_bridge.planning.planner import (
    Planner,
    PlanResult,
    PlanStatus,
    PlanStep,
    UPPlanner,
    get_planner,
    installed_planners,
)

__all__ = [
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "UPPlanner",
    "get_planner",
    "installed_planners",
]
