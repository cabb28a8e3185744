"""plan_bridge: PDDL planning with unified-planning engines, executed as SMACH machines.

The subpackages follow the pipeline, each building only on the ones before it:

1. :mod:`plan_bridge.pddl`: PDDL text -> checked :class:`PlanningTask`
   (:func:`load_task`);
2. :mod:`plan_bridge.planning`: planners under a hard time limit -> :class:`PlanResult`
   (:func:`get_planner`);
3. :mod:`plan_bridge.skills`: a SMACH skill per PDDL action (:class:`SkillRegistry`);
4. :mod:`plan_bridge.execution`: plans compiled into SMACH and run by the
   :class:`Executive` against a (simulated) world, with belief and replanning;
5. :mod:`plan_bridge.missions`: domain folders as runnable targets (:func:`load_target`);
6. :mod:`plan_bridge.cli` and :mod:`plan_bridge.study` on top; :mod:`plan_bridge.ros`
   carries missions across processes.

This module re-exports the public names lazily, so ``import plan_bridge`` does not
import unified-planning.
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
    from plan_bridge.belief import Belief
    from plan_bridge.execution.compile import compile_plan
    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.execution.simulation import SimulatedWorld
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.target import MissionSetup, Target
    from plan_bridge.pddl.task import (
        ActionSchema,
        Fact,
        PlanningTask,
        format_fact,
        load_task,
        load_task_from_text,
        parse_fact,
        task_from_problem,
    )
    from plan_bridge.planning.planner import UPPlanner
    from plan_bridge.planning.registry import get_planner, installed_planners
    from plan_bridge.planning.types import Planner, PlanResult, PlanStatus, PlanStep
    from plan_bridge.skills.registry import Skill, SkillRegistry

__version__ = "0.1.0"

_LAZY = {
    "ActionSchema": "plan_bridge.pddl.task",
    "Fact": "plan_bridge.pddl.task",
    "PlanningTask": "plan_bridge.pddl.task",
    "format_fact": "plan_bridge.pddl.task",
    "load_task": "plan_bridge.pddl.task",
    "load_task_from_text": "plan_bridge.pddl.task",
    "parse_fact": "plan_bridge.pddl.task",
    "task_from_problem": "plan_bridge.pddl.task",
    "PlanResult": "plan_bridge.planning.types",
    "PlanStatus": "plan_bridge.planning.types",
    "PlanStep": "plan_bridge.planning.types",
    "Planner": "plan_bridge.planning.types",
    "UPPlanner": "plan_bridge.planning.planner",
    "get_planner": "plan_bridge.planning.registry",
    "installed_planners": "plan_bridge.planning.registry",
    "Skill": "plan_bridge.skills.registry",
    "SkillRegistry": "plan_bridge.skills.registry",
    "Belief": "plan_bridge.belief",
    "compile_plan": "plan_bridge.execution.compile",
    "Executive": "plan_bridge.execution.executive",
    "ReplanPolicy": "plan_bridge.execution.executive",
    "SimulatedWorld": "plan_bridge.execution.simulation",
    "MissionSetup": "plan_bridge.missions.target",
    "Target": "plan_bridge.missions.target",
    "load_target": "plan_bridge.missions.mission",
}

__all__ = [
    "ActionSchema",
    "Belief",
    "Executive",
    "Fact",
    "FactError",
    "MissionSetup",
    "PddlError",
    "PlanBridgeError",
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "PlannerNotFoundError",
    "PlanningTask",
    "ReplanPolicy",
    "SimulatedWorld",
    "Skill",
    "SkillRegistry",
    "Target",
    "UPPlanner",
    "UnsupportedFeatureError",
    "WorkerError",
    "compile_plan",
    "format_fact",
    "get_planner",
    "installed_planners",
    "load_target",
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
