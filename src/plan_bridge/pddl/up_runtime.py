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
* Creating the UP environment looks for a ``up.ini`` next to the outermost
  caller's file, found with ``inspect.stack()``, which reads the source of every
  frame on the stack: 0.25 s for a short stack, more under pytest. We give it the
  same file name from ``sys._getframe`` instead.
* UP prints credits to stdout on every solve; we switch them off, so JSON output
  on stdout stays clean.
* ``Problem.initial_values`` enumerates *every* ground atom of every predicate
  (21,000 on visitall problem12) to fill in default values, and ``Problem.kind``
  recomputes from scratch on each access; UP's PDDL writer (which every PDDL-based
  engine, Fast Downward included, runs on each solve) calls both. :func:`lean_copy`
  returns a copy of a problem whose ``initial_values`` lists only what a writer or
  engine needs and whose ``kind`` is computed once: on visitall this cuts a Fast
  Downward solve through UP from ~3 s to ~0.7 s.
"""

from __future__ import annotations

import os
import sys
import threading
import types
from pathlib import PurePath
from typing import Any

__all__ = ["ensure_unified_planning", "lean_copy"]

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


def _config_locations() -> list[str]:
    """``unified_planning.engines.factory.get_possible_config_locations`` without
    ``inspect.stack()``: the same files, next to the outermost frame's file."""
    frame = sys._getframe()
    while frame.f_back is not None:
        frame = frame.f_back
    home = os.path.expanduser("~")
    files = []
    for parent in PurePath(os.path.abspath(frame.f_code.co_filename)).parents:
        files.append(os.path.join(parent, "up.ini"))
        files.append(os.path.join(parent, ".up.ini"))
    files.extend(os.path.join(home, name) for name in ("up.ini", ".up.ini", ".uprc"))
    return files


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
            from unified_planning.engines import factory  # type: ignore[import-untyped]

            factory.get_possible_config_locations = _config_locations
            import unified_planning.shortcuts  # type: ignore[import-untyped]

            environment = unified_planning.shortcuts.get_environment()
            environment.credits_stream = None
            _register_plugins()
            # Touch the factory so engine plug-ins (which also import ConfigSpace)
            # are loaded while the stand-in is in place.
            _ = environment.factory.engines
        finally:
            if installed_stand_in and isinstance(
                sys.modules.get("ConfigSpace"), _ConfigSpaceStandIn
            ):
                del sys.modules["ConfigSpace"]
        _ready = True


def _register_plugins() -> None:
    """Add engines that do not register themselves with UP's factory when imported.

    up-kairos (a temporal and numeric planner) must be registered with
    ``up_kairos.register()``; without it a user with a durative domain would have to
    know that. A missing or broken plug-in is skipped: it is then simply not listed
    among the installed planners.
    """
    import importlib.util

    if importlib.util.find_spec("up_kairos") is None:
        return
    try:
        import up_kairos  # type: ignore[import-not-found, import-untyped, unused-ignore]

        up_kairos.register()
    except Exception:  # an engine that fails to load is just not offered
        return


_lean_class: Any = None


def _lean_problem_class() -> Any:
    global _lean_class
    if _lean_class is not None:
        return _lean_class
    ensure_unified_planning()
    from unified_planning.model import Problem  # type: ignore[import-untyped]
    from unified_planning.model.fluent import get_all_fluent_exp  # type: ignore[import-untyped]

    class LeanProblem(Problem):  # type: ignore[misc]
        """A ``Problem`` with cheap ``initial_values`` and a cached ``kind``.

        ``initial_values`` holds the explicit values plus the defaults of the
        fluents whose default is not boolean false: the same values that
        ``Problem.initial_values`` has except ground atoms that are false by default,
        which PDDL writers and engines skip anyway (closed world). ``kind`` is
        computed on first access and cached: do not change the problem after that,
        except for its boolean initial values and positive goal atoms, which do not
        change the kind of a problem whose boolean fluents default to false.
        """

        _plan_bridge_kind: Any = None

        _plan_bridge_full_values = False

        @property
        def initial_values(self) -> dict[Any, Any]:
            if self._plan_bridge_full_values:
                return dict(Problem.initial_values.fget(self))
            values = dict(self._initial_value)
            defaults = self._fluent_set.fluents_defaults
            for fluent in self._fluent_set.fluents:
                default = defaults.get(fluent)
                if default is None or (fluent.type.is_bool_type() and default.is_false()):
                    continue  # no value, or false by default: nothing to add
                for fluent_exp in get_all_fluent_exp(self._object_set, fluent):
                    if fluent_exp not in values:
                        values[fluent_exp] = default
            return values

        @property
        def kind(self) -> Any:
            if self._plan_bridge_kind is None:
                self._plan_bridge_kind = Problem.kind.fget(self)
            return self._plan_bridge_kind

        def clone(self) -> Any:
            copy = Problem.clone(self)
            copy.__class__ = type(self)
            return copy

    _lean_class = LeanProblem
    return _lean_class


def lean_copy(problem: Any, *, kind: Any = None) -> Any:
    """A copy of the UP ``problem`` that is fast to write as PDDL and to solve.

    ``kind``, when given, is used as the copy's problem kind instead of computing it
    (pass the kind of the problem this one was derived from by changing only boolean
    initial values and positive goal atoms).
    """
    copy = problem.clone()
    copy.__class__ = _lean_problem_class()
    if kind is not None:
        copy._plan_bridge_kind = kind
    copy._plan_bridge_full_values = getattr(
        problem, "_plan_bridge_full_values", False
    ) or _needs_full_values(problem)
    return copy


def _needs_full_values(problem: Any) -> bool:
    """Whether engines need every ground atom's value (temporal and numeric ones do).

    TAMER converts ``initial_values`` into its own state and fails on an atom it has
    no value for (a false-by-default fact the lean view skips); its problems are
    small enough that the full enumeration costs little. Classical problems (boolean
    fluents, at most an action-cost function) keep the lean view.
    """
    from unified_planning.model import DurativeAction

    if any(isinstance(action, DurativeAction) for action in problem.actions):
        return True
    numeric = [f for f in problem.fluents if not f.type.is_bool_type()]
    return any(f.name != "total-cost" for f in numeric)
