"""Which planners there are, by name: :func:`get_planner` and :func:`installed_planners`.

One registry for every name a user can give (``--planner``, ``Executive(planner=...)``):

* ``"auto"``: :class:`~plan_bridge.planning.engines.AutoPlanner` (the engine chosen by
  the problem's kind; the warm search first during an execution);
* ``"warm-gbfs"``: :class:`~plan_bridge.planning.engines.WarmPlanner`, the warm search;
* any installed unified-planning one-shot engine (``"fast-downward"``,
  ``"pyperplan"``, ``"kairos"``...): a :class:`~plan_bridge.planning.planner.UPPlanner`.

Portfolios of Fast Downward configurations are built with
:func:`~plan_bridge.planning.portfolio.fast_downward_portfolio` from the names of
:data:`~plan_bridge.planning.portfolio.FAST_DOWNWARD_CONFIGS`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from plan_bridge.pddl.up_runtime import ensure_unified_planning
from plan_bridge.planning.worker import WorkerPool

if TYPE_CHECKING:
    from plan_bridge.planning.engines import AutoPlanner
    from plan_bridge.planning.planner import UPPlanner

__all__ = ["DEFAULT_PLANNER", "get_planner", "installed_planners", "oneshot_planners"]

DEFAULT_PLANNER = "fast-downward"


def installed_planners() -> list[str]:
    """Names of the installed unified-planning one-shot planners (meta engines such as
    ``oversubscription[fast-downward]`` are accepted by :func:`get_planner` too but not
    listed)."""
    return [name for name in oneshot_planners() if "[" not in name]


_oneshot: dict[tuple[str, ...], list[str]] = {}


def oneshot_planners() -> list[str]:
    """UP's one-shot planner engines (meta engines included), looked up once per set
    of registered engines (each lookup instantiates every engine class)."""
    ensure_unified_planning()
    from unified_planning.shortcuts import get_environment  # type: ignore[import-untyped]

    factory = get_environment().factory
    registered = tuple(factory.engines)
    cached = _oneshot.get(registered)
    if cached is None:
        cached = []
        for name in registered:
            try:
                if factory.engine(name).is_oneshot_planner():
                    cached.append(name)
            except Exception:
                continue
        _oneshot[registered] = cached
    return list(cached)


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
        from plan_bridge.planning.engines import AutoPlanner

        return AutoPlanner(pool=pool)
    if name == "warm-gbfs":
        from plan_bridge.planning.engines import WarmPlanner

        return WarmPlanner(pool=pool)
    from plan_bridge.planning.planner import UPPlanner

    return UPPlanner(name, pool=pool, params=params, label=label)
