"""Which engine plans a problem: chosen from its kind, with a fallback portfolio.

A problem's *kind* is read from unified-planning's problem kind:

* ``temporal`` when it has durative actions (UP's ``CONTINUOUS_TIME`` or
  ``DISCRETE_TIME``),
* ``numeric`` when numeric fluents appear in conditions, goals or effects other
  than action costs (``SIMPLE_NUMERIC_PLANNING``, ``GENERAL_NUMERIC_PLANNING``),
* ``classical`` otherwise (STRIPS/ADL, action costs included).

``get_planner("auto")`` returns an :class:`AutoPlanner`: classical problems go to
Fast Downward (then pyperplan, then the temporal engines, for what those refuse);
temporal and numeric ones to the installed engines of that family,
those that declare support for every feature first (Kairos, then TAMER, then
ENHSP), then the others ("trying anyway": declarations are conservative). When an
engine refuses the problem, fails or gives up without a proof, the next one is tried
within what is left of the time limit; every engine runs in a killable worker, so
engines that ignore UP's timeout (TAMER, Kairos) still stop at the deadline.
"""

from __future__ import annotations

import dataclasses
import threading
import time
import weakref
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.features import ENGINES
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask
from plan_bridge.pddl.up_runtime import ensure_unified_planning
from plan_bridge.planning.planner import PlanResult, PlanStatus, UPPlanner, installed_planners
from plan_bridge.planning.worker import WorkerPool

__all__ = [
    "AUTO",
    "AutoPlanner",
    "NoEngineError",
    "ProblemKind",
    "engines_for",
    "problem_kind",
]

#: The planner name that chooses the engine from the problem's kind.
AUTO = "auto"

_CLASSICAL = ("fast-downward", "pyperplan")
_TEMPORAL = ("kairos", "tamer", "enhsp")
_TIME = {"CONTINUOUS_TIME", "DISCRETE_TIME"}
_NUMBERS = {"SIMPLE_NUMERIC_PLANNING", "GENERAL_NUMERIC_PLANNING"}
#: Of the time left, the share an engine gets when another one could follow it.
FALLBACK_SHARE = 0.6


class NoEngineError(PlanBridgeError):
    """No installed engine can plan a problem of this kind."""


@dataclass(frozen=True)
class ProblemKind:
    """What kind of planning a problem needs, and UP's features of it."""

    temporal: bool
    numeric: bool
    features: frozenset[str]

    @property
    def name(self) -> str:
        """``classical``, ``temporal``, ``numeric`` or ``temporal+numeric``."""
        parts = [
            word for word, on in (("temporal", self.temporal), ("numeric", self.numeric)) if on
        ]
        return "+".join(parts) or "classical"

    @property
    def classical(self) -> bool:
        return not (self.temporal or self.numeric)

    def __str__(self) -> str:
        return self.name


_kinds: weakref.WeakKeyDictionary[PlanningTask, ProblemKind] = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def problem_kind(task: PlanningTask) -> ProblemKind:
    """The kind of ``task`` (computed once per task: UP's kind costs up to ~0.2 s)."""
    with _lock:
        cached = _kinds.get(task)
    if cached is not None:
        return cached
    ensure_unified_planning()
    features = frozenset(task.problem.kind.features)
    kind = ProblemKind(bool(features & _TIME), bool(features & _NUMBERS), features)
    with _lock:
        _kinds[task] = kind
    return kind


def engines_for(task: PlanningTask) -> list[str]:
    """Installed engines to try on ``task``, best first; raises :class:`NoEngineError`
    naming the features and the packages to install when there is none."""
    kind = problem_kind(task)
    installed = set(installed_planners())
    if kind.classical:
        # Then the temporal+numeric engines, which plan classical problems too: what
        # the classical ones refuse (a makespan metric, a number set in :init that no
        # action uses: Fast Downward's translator fails on both) still gets planned.
        family = [name for name in (*_CLASSICAL, *_TEMPORAL) if name in installed]
    else:
        family = [name for name in _TEMPORAL if name in installed]
    if not family:
        wanted = _CLASSICAL if kind.classical else _TEMPORAL
        packages = ", ".join(f"{ENGINES[n].package} ({n})" for n in wanted if n in ENGINES)
        lacking = sorted(kind.features & (_TIME | _NUMBERS)) or ["classical planning"]
        raise NoEngineError(
            f"no installed planner can plan this {kind.name} problem "
            f"({', '.join(lacking)}); install one of: {packages}"
        )
    from unified_planning.shortcuts import get_environment  # type: ignore[import-untyped]

    factory = get_environment().factory
    problem_kind_up = task.problem.kind
    declared = [n for n in family if factory.engine(n).supports(problem_kind_up)]
    return declared + [n for n in family if n not in declared]


class AutoPlanner:
    """Plans each task with the engines :func:`engines_for` names, in turn.

    The result's ``planner`` is the engine that answered; ``warnings`` say which
    engines were tried before it and why they gave up.
    """

    def __init__(
        self,
        *,
        pool: WorkerPool | None = None,
        engines: Iterable[str] | None = None,
        params: Mapping[str, Mapping[str, object]] | None = None,
    ) -> None:
        self._pool = pool
        self._fixed = list(engines) if engines is not None else None
        for name in self._fixed or ():
            UPPlanner(name, pool=pool)  # raises PlannerNotFoundError for an unknown name
        self._params = {k: dict(v) for k, v in (params or {}).items()}
        self._planners: dict[str, UPPlanner] = {}
        self._lock = threading.Lock()

    @property
    def name(self) -> str:
        return AUTO if self._fixed is None else "portfolio[" + ",".join(self._fixed) + "]"

    def __repr__(self) -> str:
        return f"AutoPlanner(engines={self._fixed!r})"

    def engines(self, task: PlanningTask) -> list[str]:
        """The engines this planner tries on ``task``, in order."""
        return list(self._fixed) if self._fixed is not None else engines_for(task)

    def planner(self, engine: str) -> UPPlanner:
        with self._lock:
            planner = self._planners.get(engine)
            if planner is None:
                planner = UPPlanner(engine, pool=self._pool, params=self._params.get(engine))
                self._planners[engine] = planner
            return planner

    def warm_up(self) -> None:
        (self._pool or _default_pool()).warm_up(1)

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float = 60.0,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
        cancel: threading.Event | None = None,
        values: Mapping[Fact, float] | None = None,
    ) -> PlanResult:
        """Plan with the first engine, then the next while they refuse or fail.

        Engines but the last get :data:`FALLBACK_SHARE` of the time left, so one that
        hangs leaves time to the next. A proof of unsolvability, a timeout of the
        last engine or a cancel ends the search.
        """
        if timeout <= 0:
            raise ValueError(f"timeout must be positive, got {timeout!r}")
        started = time.monotonic()
        deadline = started + timeout
        engines = self.engines(task)
        if values is None and isinstance(getattr(initial_state, "values", None), Mapping):
            values = initial_state.values  # type: ignore[union-attr]  # a belief snapshot
        facts = None if initial_state is None else list(initial_state)
        atoms = None if goal is None else list(goal)
        tried: list[str] = []
        result: PlanResult | None = None
        searched: PlanResult | None = None  # the last engine that searched and found none
        for number, engine in enumerate(engines):
            left = deadline - time.monotonic()
            if left <= 0.05 or (cancel is not None and cancel.is_set()):
                break
            last = number == len(engines) - 1
            budget = left if last else left * FALLBACK_SHARE
            result = self.planner(engine).solve(
                task,
                timeout=budget,
                initial_state=facts,
                goal=atoms,
                cancel=cancel,
                values=values,
            )
            if result.solved or _final(result):
                break
            if result.status is not PlanStatus.UNSUPPORTED:
                searched = result
            tried.append(f"{engine}: {result.status.value}: {_first(result.explanation)}")
        if result is None:
            raise NoEngineError("no planner was tried: the time limit was already spent")
        if result.status is PlanStatus.UNSUPPORTED and searched is not None:
            # A later engine refusing the problem says nothing about it: the reason is
            # what the engine that did search found (its refusal stays a note).
            result = searched
        notes = [f"tried first: {line}" for line in tried if not line.startswith(result.planner)]
        return dataclasses.replace(
            result,
            planning_time_s=time.monotonic() - started,
            warnings=tuple(dict.fromkeys((*notes, *result.warnings))),
        )


def _final(result: PlanResult) -> bool:
    """Whether another engine could not do better: a proof, or the caller's cancel."""
    if result.status is PlanStatus.UNSOLVABLE and (
        result.engine_status == "UNSOLVABLE_PROVEN" or result.unreachable_goals
    ):
        return True
    return result.status is PlanStatus.TIMEOUT and "cancelled" in result.explanation


def _first(text: str) -> str:
    stripped = text.strip()
    return stripped.splitlines()[0][:200] if stripped else ""


def _default_pool() -> WorkerPool:
    from plan_bridge.planning.worker import default_pool

    return default_pool()
