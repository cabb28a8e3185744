"""Which engine plans a problem: chosen from its kind, with a fallback portfolio.

A problem's *kind* is read from unified-planning's problem kind:

* ``temporal`` when it has durative actions (UP's ``CONTINUOUS_TIME`` or
  ``DISCRETE_TIME``),
* ``numeric`` when numeric fluents appear in conditions, goals or effects other
  than action costs (``SIMPLE_NUMERIC_PLANNING``, ``GENERAL_NUMERIC_PLANNING``),
* ``classical`` otherwise (STRIPS/ADL, action costs included).

``get_planner("auto")`` returns an :class:`AutoPlanner`: classical problems go to
Fast Downward (then pyperplan, then the temporal engines, for what those refuse);
during an execution (:meth:`AutoPlanner.for_execution`) to the warm search first
when it handles their constructs (:class:`WarmPlanner`: a greedy search inside the
planner worker, no new process; it gets at most :data:`WARM_BUDGET_S`, and a task it
gave up on goes straight to Fast Downward afterwards). Fast Downward goes first for
action costs, which UP says it does not support although it solves them. Temporal
and numeric problems go to the installed engines of that family,
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
from plan_bridge.planning.grounding import UnsupportedProblemError
from plan_bridge.planning.types import PlanResult, PlanStatus, snapshot_values
from plan_bridge.planning.up_planner import SolveRequest, UPPlanner, installed_planners, up_kind
from plan_bridge.planning.warm import WARM, WarmState, solve_warm
from plan_bridge.planning.worker import ProblemText, SolveReply, WorkerPool

__all__ = [
    "AUTO",
    "WARM",
    "WARM_BUDGET_S",
    "AutoPlanner",
    "NoEngineError",
    "ProblemKind",
    "WarmPlanner",
    "engines_for",
    "problem_kind",
    "warm_unsupported",
]

#: The planner name that chooses the engine from the problem's kind.
AUTO = "auto"

_CLASSICAL = ("fast-downward", "pyperplan")
_TEMPORAL = ("kairos", "tamer", "enhsp")
_TIME = {"CONTINUOUS_TIME", "DISCRETE_TIME"}
_NUMBERS = {"SIMPLE_NUMERIC_PLANNING", "GENERAL_NUMERIC_PLANNING"}
#: Of the time left, the share an engine gets when another one could follow it.
FALLBACK_SHARE = 0.6
#: The most time the warm search gets before Fast Downward takes over (seconds).
WARM_BUDGET_S = 0.1


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
_orders: weakref.WeakKeyDictionary[PlanningTask, tuple[str, ...]] = weakref.WeakKeyDictionary()
#: Tasks the warm search gave up on (budget spent, too big): Fast Downward's from then on.
_warm_failed: weakref.WeakSet[PlanningTask] = weakref.WeakSet()
#: The warm search's state per task when it runs in this process (cold starts).
_local_warm: weakref.WeakKeyDictionary[PlanningTask, WarmState] = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def problem_kind(task: PlanningTask) -> ProblemKind:
    """The kind of ``task`` (computed once per task: UP's kind costs up to ~0.2 s)."""
    with _lock:
        cached = _kinds.get(task)
    if cached is not None:
        return cached
    ensure_unified_planning()
    features = frozenset(up_kind(task).features)
    kind = ProblemKind(bool(features & _TIME), bool(features & _NUMBERS), features)
    with _lock:
        _kinds[task] = kind
    return kind


def engines_for(task: PlanningTask, *, warm: bool = False) -> list[str]:
    """Installed engines to try on ``task``, best first; raises :class:`NoEngineError`
    naming the features and the packages to install when there is none.

    With ``warm``, the warm search comes first for a classical problem it handles
    (and has not given up on before)."""
    with _lock:
        order = _orders.get(task)
        warm_failed = task in _warm_failed
    if order is None:
        order = tuple(_engine_order(task))  # UP's problem kind: computed once per task
        with _lock:
            _orders[task] = order
    if warm and not warm_failed and not warm_unsupported(task):
        return [WARM, *order]
    return list(order)


def _engine_order(task: PlanningTask) -> list[str]:
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
    problem_kind_up = up_kind(task)
    declared = [
        n
        for n in family
        if factory.engine(n).supports(problem_kind_up)
        or (n == "fast-downward" and _costs_only(factory.engine(n), problem_kind_up))
    ]
    return declared + [n for n in family if n not in declared]


def _costs_only(engine: object, kind: object) -> bool:
    """Whether all ``engine`` lacks for ``kind`` is action costs read from PDDL: UP
    declares Fast Downward unsuitable for them, yet it solves them (elevators: 0.25 s,
    where Kairos, which declares them, takes 20-30 s)."""
    try:
        lacking = set(kind.features) - set(engine.supported_kind().features)  # type: ignore[attr-defined]
    except Exception:  # meta engines need a concrete problem to answer
        return False
    return bool(lacking) and all("COST" in f or f == "UNDEFINED_INITIAL_NUMERIC" for f in lacking)


class AutoPlanner:
    """Plans each task with the engines :func:`engines_for` names, in turn.

    The result's ``planner`` is the engine that answered; ``warnings`` say which
    engines were tried before it and why they gave up. With ``warm`` (what an
    execution uses: :meth:`for_execution`), classical problems the warm search
    handles go to it first: a replan then costs milliseconds instead of a Fast
    Downward process. Without it (a one-shot ``plan-bridge plan``), Fast Downward
    plans them, as its plans are often shorter.
    """

    def __init__(
        self,
        *,
        pool: WorkerPool | None = None,
        engines: Iterable[str] | None = None,
        params: Mapping[str, Mapping[str, object]] | None = None,
        warm: bool = False,
    ) -> None:
        self.warm = warm
        self._pool = pool
        self._fixed = list(engines) if engines is not None else None
        for name in self._fixed or ():
            if name != WARM:
                UPPlanner(name, pool=pool)  # raises PlannerNotFoundError for an unknown name
        self._params = {k: dict(v) for k, v in (params or {}).items()}
        self._planners: dict[str, UPPlanner] = {}
        self._lock = threading.Lock()

    @property
    def name(self) -> str:
        return AUTO if self._fixed is None else "portfolio[" + ",".join(self._fixed) + "]"

    def __repr__(self) -> str:
        return f"AutoPlanner(engines={self._fixed!r}, warm={self.warm!r})"

    def for_execution(self) -> AutoPlanner:
        """This planner with the warm search first (the same pool and engines)."""
        if self.warm:
            return self
        planner = AutoPlanner(pool=self._pool, engines=self._fixed, params=self._params, warm=True)
        planner._planners = self._planners  # the same planner objects, their caches too
        planner._lock = self._lock
        return planner

    def engines(self, task: PlanningTask) -> list[str]:
        """The engines this planner tries on ``task``, in order."""
        if self._fixed is not None:
            return list(self._fixed)
        return engines_for(task, warm=self.warm)

    def planner(self, engine: str) -> UPPlanner:
        with self._lock:
            planner = self._planners.get(engine)
            if planner is None:
                if engine == WARM:
                    planner = WarmPlanner(pool=self._pool, budget=WARM_BUDGET_S)
                else:
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
        # The warm search first needs no engine list (UP's problem kind costs ~30 ms).
        engines = [WARM] if self._warm_first(task) else self.engines(task)
        values = snapshot_values(initial_state, values)
        request = _Request(
            None if initial_state is None else list(initial_state),
            None if goal is None else list(goal),
            values,
            cancel,
        )
        tried: list[str] = []
        result: PlanResult | None = None
        searched: PlanResult | None = None  # the last engine that searched and found none
        index = 0
        while index < len(engines):
            engine = engines[index]
            index += 1
            left = deadline - time.monotonic()
            if left <= 0.05 or (cancel is not None and cancel.is_set()):
                break
            # (The warm search keeps to its own budget, WARM_BUDGET_S, once the worker
            # has the problem parsed: the parse may take longer than the search.)
            budget = left if index == len(engines) and engine != WARM else left * FALLBACK_SHARE
            result = self._attempt(engine, task, budget, request)
            if result.solved or _final(result):
                break
            if engine == WARM:
                engines.extend(self._after_warm(task))
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

    def _warm_first(self, task: PlanningTask) -> bool:
        if self._fixed is not None or not self.warm:
            return False
        with _lock:
            if task in _warm_failed:
                return False
        return not warm_unsupported(task)

    def _after_warm(self, task: PlanningTask) -> list[str]:
        """The engines after a warm search that gave up (which it will not try again
        on this task); none when no engine is installed."""
        with _lock:
            _warm_failed.add(task)
        if self._fixed is not None:
            return []
        try:
            return engines_for(task)
        except NoEngineError:
            return []

    def _attempt(
        self, engine: str, task: PlanningTask, budget: float, request: _Request
    ) -> PlanResult:
        return self.planner(engine).solve(
            task,
            timeout=budget,
            initial_state=request.facts,
            goal=request.goal,
            cancel=request.cancel,
            values=request.values,
        )


@dataclass(frozen=True)
class _Request:
    facts: list[FactLike] | None
    goal: list[FactLike] | None
    values: Mapping[Fact, float] | None
    cancel: threading.Event | None


def warm_unsupported(task: PlanningTask) -> str:
    """Why the warm search does not plan ``task`` (empty when it does): its own
    compilation of the actions decides (cached per task; no UP problem kind)."""
    state = _local_state(task)
    with state.lock:
        try:
            state.lifted(task.problem)
        except UnsupportedProblemError as exc:
            return str(exc)
    return ""


def _local_state(task: PlanningTask) -> WarmState:
    with _lock:
        state = _local_warm.get(task)
        if state is None:
            state = _local_warm[task] = WarmState()
        return state


class WarmPlanner(UPPlanner):
    """The warm search (:mod:`plan_bridge.planning.warm`): a greedy best-first search
    with the FF heuristic, run inside a planner worker on the problem it has parsed
    and grounded before, so a replan starts no process. Classical problems only
    (:func:`warm_unsupported` says why not); its plans are checked before they are sent.
    """

    needs_workdir = False

    def __init__(
        self,
        *,
        pool: WorkerPool | None = None,
        explain_timeout: float = 5.0,
        budget: float | None = None,
    ) -> None:
        """``budget``: seconds of grounding and search (from when the worker has the
        problem parsed), within the solve's ``timeout`` (the hard limit)."""
        params = None if budget is None else {"budget_s": budget}
        super().__init__(WARM, pool=pool, explain_timeout=explain_timeout, params=params)

    @staticmethod
    def _check_engine(engine: str) -> None:
        """The warm search is always there (it is not a unified-planning engine)."""

    def __repr__(self) -> str:
        return "WarmPlanner()"

    def unsupported_features(self, task: PlanningTask) -> list[str]:
        reason = warm_unsupported(task)
        return [reason] if reason else []

    def _solve_here(
        self, task: PlanningTask, text: ProblemText, request: SolveRequest, timeout: float
    ) -> SolveReply | None:
        """While no worker has started yet (a cold start), search in this process: the
        search keeps to its deadline, and waiting for a process to start costs more
        than the search. Tasks read from PDDL only (their names are the UP problem's).
        A problem with constructs the warm search does not handle is refused at once."""
        reason = warm_unsupported(task)
        if reason:
            return SolveReply(
                "result", "UNSUPPORTED_PROBLEM", message=f"{WARM} does not handle: {reason}"
            )
        if task.domain_text is None or request.values or self.pool.has_ready_worker():
            return None
        state = task.initial_facts if request.init is None else map(tuple, request.init)
        goal = None if request.goal is None else [tuple(atom) for atom in request.goal]
        cache = _local_state(task)
        with cache.lock:
            answer = solve_warm(task.problem, cache, state, goal, _budget(self.params, timeout))
        return SolveReply(
            outcome=str(answer["outcome"]),
            status=str(answer["status"]),
            plan=tuple((str(name), tuple(args)) for name, args in answer["plan"]),
            message=str(answer["message"]),
            log=str(answer["log"]),
            engine_time_s=float(answer["engine_time_s"]),
        )

    def _interpret(
        self,
        task: PlanningTask,
        started: float,
        timeout: float,
        reply: SolveReply,
        writer: object,
        notes: list[str],
        missing: list[str],
    ) -> PlanResult:
        # A spent budget or a refusal is the cue for Fast Downward: no analysis.
        if reply.outcome == "result" and reply.status in ("TIMEOUT", "UNSUPPORTED_PROBLEM"):
            status = PlanStatus.TIMEOUT if reply.status == "TIMEOUT" else PlanStatus.UNSUPPORTED
            return self._finish(
                task,
                started,
                status,
                reply.message or f"{WARM}: {reply.status.lower()}",
                notes,
                reply=reply,
            )
        return super()._interpret(task, started, timeout, reply, writer, notes, missing)


def _budget(params: Mapping[str, object] | None, timeout: float) -> float:
    budget = (params or {}).get("budget_s")
    return min(timeout, float(budget)) if isinstance(budget, (int, float)) else timeout


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
