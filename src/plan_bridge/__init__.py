"""plan_bridge: PDDL planning with unified-planning engines, executed as SMACH machines.

Foundation layer (this module re-exports it lazily, so ``import plan_bridge`` does
not import unified-planning):

* :func:`load_task` / :func:`task_from_problem` -> :class:`PlanningTask`
  (``plan_bridge.domain``),
* :func:`get_planner` -> :class:`Planner` whose ``solve`` returns a
  :class:`PlanResult` (``plan_bridge.planning``),
* the exceptions in ``plan_bridge.errors``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from plan_bridge.errors import (
    FactError,
    PddlError,
    PlanBridgeError,
    PlannerNotFoundError,
    UnsupportedFeatureError,
    WorkerError,
)

if TYPE_CHECKING:
    from plan_bridge.domain import (
        ActionSchema,
        Fact,
        PlanningTask,
        format_fact,
        load_task,
        load_task_from_text,
        parse_fact,
        task_from_problem,
    )
    from plan_bridge.planning import (
        Planner,
        PlanResult,
        PlanStatus,
        PlanStep,
        UPPlanner,
        get_planner,
        installed_planners,
    )

__version__ = "0.1.0"

_LAZY = {
    "ActionSchema": "plan_bridge.domain",
    "Fact": "plan_bridge.domain",
    "PlanningTask": "plan_bridge.domain",
    "format_fact": "plan_bridge.domain",
    "load_task": "plan_bridge.domain",
    "load_task_from_text": "plan_bridge.domain",
    "parse_fact": "plan_bridge.domain",
    "task_from_problem": "plan_bridge.domain",
    "PlanResult": "plan_bridge.planning",
    "PlanStatus": "plan_bridge.planning",
    "PlanStep": "plan_bridge.planning",
    "Planner": "plan_bridge.planning",
    "UPPlanner": "plan_bridge.planning",
    "get_planner": "plan_bridge.planning",
    "installed_planners": "plan_bridge.planning",
}

__all__ = [
    "ActionSchema",
    "Fact",
    "FactError",
    "PddlError",
    "PlanBridgeError",
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "PlannerNotFoundError",
    "PlanningTask",
    "UPPlanner",
    "UnsupportedFeatureError",
    "WorkerError",
    "format_fact",
    "get_planner",
    "installed_planners",
    "load_task",
    "load_task_from_text",
    "parse_fact",
    "task_from_problem",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'plan_bridge' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
