"""Stage 2, planning: planners under a hard time limit, and the plans they return.

``from plan_bridge.planning import get_planner`` is the public entry. The modules:

* :mod:`.types`: :class:`PlanResult`, :class:`PlanStep`, :class:`PlanStatus` and the
  :class:`Planner` protocol;
* :mod:`.registry`: :func:`get_planner` (every planner name) and
  :func:`installed_planners`;
* :mod:`.up_planner`: unified-planning engines (:class:`UPPlanner`) and which are
  installed;
* :mod:`.planner`: a front re-exporting the names above, where older code imports them;
* :mod:`.engines`: ``auto`` (the engine by the problem's kind) and the warm search's
  client (:class:`~plan_bridge.planning.engines.WarmPlanner`);
* :mod:`.portfolio`: racing Fast Downward configurations;
* :mod:`.worker` and :mod:`.service`: the worker processes (client and server side);
* :mod:`.warm`, :mod:`.grounding` and :mod:`.search`: the warm search that runs in
  them.
"""

from __future__ import annotations

from plan_bridge.planning.registry import get_planner, installed_planners
from plan_bridge.planning.types import Planner, PlanResult, PlanStatus, PlanStep
from plan_bridge.planning.up_planner import UPPlanner

__all__ = [
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "UPPlanner",
    "get_planner",
    "installed_planners",
]
