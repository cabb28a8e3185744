"""Importing unified-planning: lazily, quietly and fast.

Two quirks of unified-planning 1.3 shape this module:

* Creating the UP environment imports ``unified_planning.engines.engine``, which
  does ``from ConfigSpace import ConfigurationSpace``; ConfigSpace imports
  scipy.stats, which costs 1.5-2.5 s here, although ``ConfigurationSpace`` is only
  used by ``Engine.get_configuration_space()`` (engine tuning). While UP is being
  imported we put a stand-in ``ConfigSpace`` module in ``sys.modules`` whose
  ``ConfigurationSpace`` imports the real package on first use; afterwards the
  stand-in is removed so later ``import ConfigSpace`` gets the real module. This
  cuts the UP import from ~2 s to ~0.5 s, which matters for the CLI and for every
  planner worker process.
* UP prints credits to stdout on every solve; we switch them off, so JSON output
  on stdout stays clean.
"""

from __future__ import annotations

import sys
import threading
import types
from typing import Any

__all__ = ["ensure_unified_planning"]

_lock = threading.Lock()
_ready = False


class _LazyConfigurationSpace:
    """Stand-in for ``ConfigSpace.ConfigurationSpace`` that builds the real thing."""

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        if isinstance(sys.modules.get("ConfigSpace"), _ConfigSpaceStandIn):
            del sys.modules["ConfigSpace"]
        import ConfigSpace

        return ConfigSpace.ConfigurationSpace(*args, **kwargs)


class _ConfigSpaceStandIn(types.ModuleType):
    pass


def ensure_unified_planning() -> None:
    """Import unified-planning (once per process) with credits switched off."""
    global _ready
    if _ready:
        return
    with _lock:
        if _ready:
            return
        installed_stand_in = False
        if "ConfigSpace" not in sys.modules:
            stand_in = _ConfigSpaceStandIn("ConfigSpace")
            stand_in.ConfigurationSpace = _LazyConfigurationSpace  # type: ignore[attr-defined]
            sys.modules["ConfigSpace"] = stand_in
            installed_stand_in = True
        try:
            import unified_planning.shortcuts  # type: ignore[import-untyped]

            environment = unified_planning.shortcuts.get_environment()
            environment.credits_stream = None
            # Touch the factory so engine plug-ins (which also import ConfigSpace)
            # are loaded while the stand-in is in place.
            _ = environment.factory.engines
        finally:
            if installed_stand_in and isinstance(
                sys.modules.get("ConfigSpace"), _ConfigSpaceStandIn
            ):
                del sys.modules["ConfigSpace"]
        _ready = True
