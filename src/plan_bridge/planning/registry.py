"""Which planners there are, by name: :func:`get_planner` and :func:`installed_planners`.

One registry for every name a user can give (``--planner``, ``Executive(planner=...)``):

* ``"auto"``: :class:`~plan_bridge.planning.engines.AutoPlanner` (the engine chosen by
  the problem's kind; the warm search first during an execution);
* ``"warm-gbfs"``: :class:`~plan_bridge.planning.engines.WarmPlanner`, the warm search;
* any installed unified-planning one-shot engine (``"fast-downward"``,
  ``"pyperplan"``, ``"kairos"``...): a :class:`~plan_bridge.planning.up_planner.UPPlanner`.

Portfolios of Fast Downward configurations are built with
:func:`~plan_bridge.planning.portfolio.fast_downward_portfolio` from the names of
:data:`~plan_bridge.planning.portfolio.FAST_DOWNWARD_CONFIGS`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from plan_bridge.planning.engines import AutoPlanner, WarmPlanner
from plan_bridge.planning.up_planner import (
    DEFAULT_PLANNER,
    UPPlanner,
    installed_planners,
    oneshot_planners,
)
from plan_bridge.planning.worker import WorkerPool

__all__ = ["DEFAULT_PLANNER", "get_planner", "installed_planners", "oneshot_planners"]


def get_planner(
    name: str = DEFAULT_PLANNER,
    *,
    pool: WorkerPool | None = None,
    params: Mapping[str, Any] | None = None,
    label: str | None = None,
) -> UPPlanner | AutoPlanner:
    """The planner called ``name``; raises :class:`PlannerNotFoundError` listing the
    installed ones if there is none. ``params`` configure the engine, ``label`` names
    that configuration (see :class:`UPPlanner`). ``"auto"`` chooses the engine from
    each problem's kind (:class:`~plan_bridge.planning.engines.AutoPlanner`)."""
    if name == "auto":
        return AutoPlanner(pool=pool)
    if name == "warm-gbfs":
        return WarmPlanner(pool=pool)
    return UPPlanner(name, pool=pool, params=params, label=label)
