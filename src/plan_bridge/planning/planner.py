"""Planners: unified-planning engines behind one protocol, with hard time limits.

>>> task = load_task("domain.pddl", "problem.pddl")          # doctest: +SKIP
>>> result = get_planner("fast-downward").solve(task, timeout=10)  # doctest: +SKIP
>>> [str(step) for step in result.actions]                  # doctest: +SKIP
['(pick ball1 rooma left)', ...]

"No plan" is a :class:`PlanResult`, never an exception: its ``status`` says what
happened (unsolvable, timeout, unsupported, error) and ``explanation`` says why,
e.g. the goal atoms that are unreachable even under delete relaxation.

Every solve runs in a warm worker process (:mod:`plan_bridge.planning.worker`) that is
killed at the deadline, so ``timeout`` holds for engines that ignore it.

(Over 600 lines: the protocol, its result types and the unified-planning adapter
that fills them are read together; the process pool lives in
:mod:`plan_bridge.planning.worker` and engine choice in :mod:`.engines`.)
"""

from __future__ import annotations

import dataclasses
import enum
import threading
import time
import weakref
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from plan_bridge.errors import PlannerNotFoundError
from plan_bridge.pddl.initial_values import NO_INITIAL_VALUE
from plan_bridge.pddl.reachability import ReachabilityReport, relaxed_unreachable_goals
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask, format_fact
from plan_bridge.pddl.up_runtime import ensure_unified_planning
from plan_bridge.planning.problem_source import problem_source as _problem_source
from plan_bridge.planning.worker import SolveReply, WorkerPool, default_pool

if TYPE_CHECKING:
    from plan_bridge.planning.engines import AutoPlanner

__all__ = [
    "DEFAULT_PLANNER",
    "PlanResult",
    "PlanStatus",
    "PlanStep",
    "Planner",
    "UPPlanner",
    "get_planner",
    "installed_planners",
]

DEFAULT_PLANNER = "fast-downward"

# Engines that warn they ignore UP's timeout: the worker kill enforces it anyway,
# so the warning is noise for our users.
_IGNORED_WARNINGS = ("does not support timeout",)


class PlanStatus(str, enum.Enum):
    """What a solve ended with."""

    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    TIMEOUT = "timeout"
    ERROR = "error"
    UNSUPPORTED = "unsupported"


@dataclass(frozen=True)
class PlanStep:
    """One ground action of a plan: ``PlanStep("pick", ("cup", "table"))``.

    Steps of a temporal plan also carry their planned ``start`` and ``duration``
    (plan time, seconds); they do not take part in equality, so a step is the same
    action whenever it is planned.
    """

    action: str
    arguments: tuple[str, ...] = ()
    start: float | None = field(default=None, compare=False)
    duration: float | None = field(default=None, compare=False)

    def __str__(self) -> str:
        return "(" + " ".join((self.action, *self.arguments)) + ")"


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one solve."""

    status: PlanStatus
    actions: list[PlanStep] = field(default_factory=list)
    planner: str = ""
    planning_time_s: float = 0.0
    """Wall-clock time of the whole ``solve`` call (PDDL writing, worker, analysis)."""
    explanation: str = ""
    """Why there is no plan (empty when solved)."""
    warnings: tuple[str, ...] = ()
    """Warnings of unified-planning and the engine during this solve."""
    unreachable_goals: tuple[Fact, ...] = ()
    """Goal atoms unreachable under delete relaxation (when that was the reason)."""
    engine_status: str = ""
    """The engine's own status (UP ``PlanGenerationResultStatus`` name)."""
    engine_time_s: float = 0.0
    """Time spent in the engine inside the worker."""
    log: str = ""
    """The tail of the engine's log."""
    problem_reused: bool = False
    """True when the worker derived the problem from one it had parsed before (a
    replan's fast path: no PDDL parsing)."""

    @property
    def solved(self) -> bool:
        return self.status is PlanStatus.SOLVED

    def plan_strings(self) -> list[str]:
        return [str(step) for step in self.actions]

    @property
    def temporal(self) -> bool:
        """Whether the plan is time-triggered (its steps have start times)."""
        return any(step.start is not None for step in self.actions)

    @property
    def makespan(self) -> float | None:
        """When the last action of a temporal plan ends (plan time); None otherwise."""
        if not self.temporal:
            return None
        return max(((s.start or 0.0) + (s.duration or 0.0) for s in self.actions), default=0.0)

    def to_json(self) -> dict[str, Any]:
        """A JSON-serialisable summary (the shape of ``plan-bridge plan --json``)."""
        return {
            "status": self.status.value,
            "planner": self.planner,
            "planning_time_s": round(self.planning_time_s, 4),
            "plan_length": len(self.actions),
            "plan": self.plan_strings(),
            "explanation": self.explanation,
            "unreachable_goals": [format_fact(goal) for goal in self.unreachable_goals],
            "warnings": list(self.warnings),
            "engine_status": self.engine_status,
            **self._timing_json(),
        }

    def _timing_json(self) -> dict[str, Any]:
        if not self.temporal:
            return {}
        return {
            "actions": [
                {"action": str(step), "start": step.start, "duration": step.duration}
                for step in self.actions
            ],
            "makespan": self.makespan,
        }


@runtime_checkable
class Planner(Protocol):
    """Anything that turns a :class:`PlanningTask` into a :class:`PlanResult`."""

    @property
    def name(self) -> str: ...

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
    ) -> PlanResult:
        """Plan for ``task``; ``initial_state`` (true ground facts) replaces the
        task's initial state for this solve (closed world), and ``goal`` (ground
        atoms) replaces its goal by their conjunction."""
        ...


def installed_planners() -> list[str]:
    """Names of the installed unified-planning one-shot planners (meta engines such as
    ``oversubscription[fast-downward]`` are accepted by :func:`get_planner` too but not
    listed)."""
    return [name for name in _oneshot_planners() if "[" not in name]


def _oneshot_planners() -> list[str]:
    ensure_unified_planning()
    from unified_planning.shortcuts import get_environment  # type: ignore[import-untyped]

    factory = get_environment().factory
    names = []
    for name in factory.engines:
        try:
            if factory.engine(name).is_oneshot_planner():
                names.append(name)
        except Exception:
            continue
    return names


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
    return UPPlanner(name, pool=pool, params=params, label=label)


class UPPlanner:
    """A unified-planning one-shot planner engine, run in a killable worker process.

    ``engine`` is a UP engine name: ``"fast-downward"`` (default),
    ``"fast-downward-opt"``, ``"pyperplan"``, ``"pyperplan-opt"`` or any other
    installed one-shot planner. ``explain_timeout`` bounds the delete-relaxation
    analysis that explains a "no plan" answer. ``params`` go to the engine as UP's
    ``OneshotPlanner(params=...)`` (for Fast Downward e.g.
    ``{"fast_downward_search_config": "..."}``); ``label`` is then the planner's
    :attr:`name` (default: the engine name).
    """

    def __init__(
        self,
        engine: str = DEFAULT_PLANNER,
        *,
        pool: WorkerPool | None = None,
        explain_timeout: float = 5.0,
        params: Mapping[str, Any] | None = None,
        label: str | None = None,
    ) -> None:
        available = _oneshot_planners()
        if engine not in available:
            raise PlannerNotFoundError(engine, [n for n in available if "[" not in n])
        self._engine = engine
        self.params = dict(params or {})
        self._label = label or engine
        self._pool = pool
        self.explain_timeout = explain_timeout
        self._unsupported: weakref.WeakKeyDictionary[PlanningTask, list[str]] = (
            weakref.WeakKeyDictionary()
        )

    @property
    def name(self) -> str:
        return self._label

    @property
    def engine(self) -> str:
        """The unified-planning engine name (``name`` may be a configuration's label)."""
        return self._engine

    def __repr__(self) -> str:
        extra = f", params={self.params!r}" if self.params else ""
        return f"UPPlanner({self._engine!r}{extra})"

    @property
    def pool(self) -> WorkerPool:
        return self._pool if self._pool is not None else default_pool()

    def warm_up(self) -> None:
        """Start a worker process now, so the first solve does not wait for it."""
        self.pool.warm_up(1)

    def supporting_engines(self, task: PlanningTask) -> list[str]:
        """Installed planners whose declared capabilities cover ``task``."""
        ensure_unified_planning()
        from unified_planning.shortcuts import get_environment

        factory = get_environment().factory
        kind = task.problem.kind
        return [name for name in installed_planners() if factory.engine(name).supports(kind)]

    def _alternatives(self, task: PlanningTask) -> str:
        supporting = [n for n in self.supporting_engines(task) if n != self._engine]
        lacking = _lacking(DEFAULT_PLANNER, task)
        if (
            DEFAULT_PLANNER not in supporting
            and self._engine != DEFAULT_PLANNER
            and lacking
            and all("COST" in f or f == "UNDEFINED_INITIAL_NUMERIC" for f in lacking)
        ):
            # UP declares Fast Downward unsuitable for action costs read from PDDL,
            # yet it solves them (see the warnings of its results).
            supporting.insert(0, DEFAULT_PLANNER)
        if supporting:
            return f"Installed planners that support it: {', '.join(supporting)}"
        others = []
        for name in installed_planners():
            if name != self._engine:
                lacking = UPPlanner(name, pool=self._pool).unsupported_features(task)
                others.append((len(lacking), name, lacking))
        if not others:
            return "No other planner is installed"
        _, name, lacking = min(others)
        return (
            f"No installed planner declares full support; {name} lacks the fewest features "
            f"({', '.join(lacking)}) and may still solve it"
        )

    def unsupported_features(self, task: PlanningTask) -> list[str]:
        """Features of ``task`` this engine does not declare support for."""
        return _lacking(self._engine, task)

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
        """Plan for ``task`` within ``timeout`` seconds of engine wall-clock time.

        ``values`` (numeric atom -> number) replaces the initial values of those
        numeric fluents (a replan from a belief that holds numbers).

        ``initial_state`` (true ground facts) replaces the task's initial state and
        ``goal`` (ground atoms) replaces its goal by their conjunction, for this solve.
        The worker keeps the parsed ``task`` (keyed by its PDDL text), so solving the
        same task again with other facts or goal atoms -- a replan -- does not parse
        PDDL again.

        The limit is hard: the worker is killed at the deadline and the result has
        status ``timeout``. (Starting a worker, about 0.5 s, happens before the
        clock starts; :meth:`warm_up` moves it out of the way.) Raises
        :class:`~plan_bridge.errors.FactError` for an ``initial_state`` fact or goal
        atom that does not fit the task. Setting ``cancel`` during the solve kills
        its worker; the result then has status ``timeout`` and says it was cancelled.
        """
        if timeout <= 0:
            raise ValueError(f"timeout must be positive, got {timeout!r}")
        started = time.monotonic()
        if values is None and isinstance(getattr(initial_state, "values", None), Mapping):
            # A belief's snapshot carries its numbers (plan_bridge.execution.world).
            values = initial_state.values  # type: ignore[union-attr]
        facts = (
            None
            if initial_state is None
            else frozenset(task.check_fact(fact) for fact in initial_state)
        )
        goal_atoms = None if goal is None else tuple(sorted({task.check_fact(a) for a in goal}))
        # What the explanations of a "no plan" talk about (the UP problem stays the base's).
        view = task
        if facts is not None or goal_atoms is not None:
            view = dataclasses.replace(
                task,
                initial_facts=task.initial_facts if facts is None else facts,
                goal_facts=task.goal_facts if goal_atoms is None else goal_atoms,
                goal_is_conjunctive=task.goal_is_conjunctive or goal_atoms is not None,
            )
        ensure_unified_planning()

        notes: list[str] = []
        missing = self._unsupported_cached(task)
        if missing:
            notes.append(
                f"{self._engine} does not declare support for: {', '.join(missing)}; trying anyway"
            )
        try:
            source = _problem_source(task)
        except Exception as exc:
            return self._finish(
                view,
                started,
                PlanStatus.UNSUPPORTED,
                f"cannot hand this problem to {self._engine} as PDDL: {exc}",
                notes,
            )
        notes.extend(source.notes)
        with self.pool.worker(prefer=source.text.key) as worker:
            reply = worker.solve(
                self._engine,
                source.text,
                timeout,
                init=None if facts is None else [source.pddl_atom(f) for f in sorted(facts)],
                goal=None if goal_atoms is None else [source.pddl_atom(a) for a in goal_atoms],
                values=None
                if not values
                else [[*source.pddl_atom(atom), float(v)] for atom, v in sorted(values.items())],
                params=self.params,
                cancel=cancel,
            )
        if reply.outcome == "cancelled":
            return self._finish(
                view, started, PlanStatus.TIMEOUT, f"{self.name}: {reply.message}", notes
            )
        notes.extend(w for w in reply.warnings if not any(i in w for i in _IGNORED_WARNINGS))
        result = self._interpret(view, started, timeout, reply, source.writer, notes, missing)
        return dataclasses.replace(result, problem_reused=True) if reply.reused else result

    def _unsupported_cached(self, task: PlanningTask) -> list[str]:
        # Computing a UP problem kind takes up to ~0.2 s on large problems; replans of
        # one task (other facts, positive goal atoms) have the same kind.
        with _cache_lock:
            cached = self._unsupported.get(task)
        if cached is None:
            cached = self.unsupported_features(task)
            with _cache_lock:
                self._unsupported[task] = cached
        return list(cached)

    # -- interpretation ----------------------------------------------------------
    def _interpret(
        self,
        task: PlanningTask,
        started: float,
        timeout: float,
        reply: SolveReply,
        writer: Any,
        notes: list[str],
        missing: list[str],
    ) -> PlanResult:
        if reply.outcome == "result" and reply.status.startswith("SOLVED"):
            timing = reply.timing or ((None, None),) * len(reply.plan)
            if writer is None:
                steps = [
                    PlanStep(action, args, start, duration)
                    for (action, args), (start, duration) in zip(reply.plan, timing, strict=True)
                ]
            else:
                # PDDLWriter renames what is not a valid PDDL name: map back.
                steps = [
                    PlanStep(
                        writer.get_item_named(action).name,
                        tuple(writer.get_item_named(arg).name for arg in args),
                        start,
                        duration,
                    )
                    for (action, args), (start, duration) in zip(reply.plan, timing, strict=True)
                ]
            return self._finish(
                task,
                started,
                PlanStatus.SOLVED,
                "",
                notes,
                steps=steps,
                log=reply.log,
                engine_status=reply.status,
                engine_time_s=reply.engine_time_s,
            )
        if reply.outcome == "result" and reply.status.startswith("UNSOLVABLE"):
            report = _unreachable(task, self.explain_timeout)
            verdict = (
                f"{self._engine} proved that no plan exists"
                if reply.status == "UNSOLVABLE_PROVEN"
                else f"{self._engine} found no plan (its search is incomplete, so this is "
                "not a proof)"
            )
            return self._no_plan(
                task, started, PlanStatus.UNSOLVABLE, verdict, report, notes, missing, reply
            )
        if reply.outcome == "timeout" or reply.status == "TIMEOUT":
            verdict = f"{self._engine} found no plan within the {timeout:g} s time limit"
            if reply.outcome == "timeout":
                verdict += " (the planner process was killed)"
            # A quick look may still prove the goal unreachable: then say so.
            report = _unreachable(task, min(1.0, self.explain_timeout))
            status = PlanStatus.UNSOLVABLE if report.unreachable_goals else PlanStatus.TIMEOUT
            return self._no_plan(task, started, status, verdict, report, notes, missing, reply)
        if reply.outcome == "crashed":
            return self._finish(
                task,
                started,
                PlanStatus.ERROR,
                f"{self._engine}: {reply.message}",
                notes,
                engine_status=reply.status,
                engine_time_s=reply.engine_time_s,
            )
        # The engine raised, or returned MEMOUT / INTERNAL_ERROR / UNSUPPORTED_PROBLEM.
        detail = reply.message or reply.log.strip().splitlines()[-1:] or [reply.status]
        message = detail if isinstance(detail, str) else detail[0]
        if (
            missing
            or reply.error_type == "UPUnsupportedProblemTypeError"
            or (reply.status == "UNSUPPORTED_PROBLEM")
        ):
            explanation = (
                f"{self._engine} cannot handle this problem"
                + (f": it does not support {', '.join(missing)}" if missing else "")
                + f" ({_first_line(message)}). {self._alternatives(task)}"
            )
            return self._finish(
                task,
                started,
                PlanStatus.UNSUPPORTED,
                explanation,
                notes,
                log=reply.log,
                engine_status=reply.status,
                engine_time_s=reply.engine_time_s,
            )
        kind = f"{reply.error_type}: " if reply.error_type else ""
        return self._finish(
            task,
            started,
            PlanStatus.ERROR,
            f"{self._engine} failed: {kind}{_first_line(message)}",
            notes,
            log=reply.log,
            engine_status=reply.status,
            engine_time_s=reply.engine_time_s,
        )

    def _no_plan(
        self,
        task: PlanningTask,
        started: float,
        status: PlanStatus,
        verdict: str,
        report: ReachabilityReport,
        notes: list[str],
        missing: list[str],
        reply: SolveReply,
    ) -> PlanResult:
        parts = [verdict]
        if report.unreachable_goals:
            parts.append(report.explanation())
        elif status is PlanStatus.UNSOLVABLE and report.complete:
            parts.append(
                "every goal atom is reachable when delete effects are ignored, so the "
                "conflict is between actions' delete effects or the goals themselves"
            )
        if missing:
            parts.append(
                f"note: {self._engine} does not declare support for {', '.join(missing)}, so "
                "its answer may be unreliable"
            )
        return self._finish(
            task,
            started,
            status,
            "; ".join(parts),
            notes,
            unreachable_goals=report.unreachable_goals,
            engine_status=reply.status or reply.outcome.upper(),
            engine_time_s=reply.engine_time_s,
            log=reply.log,
        )

    def _finish(
        self,
        task: PlanningTask,
        started: float,
        status: PlanStatus,
        explanation: str,
        notes: list[str],
        *,
        steps: list[PlanStep] | None = None,
        unreachable_goals: tuple[Fact, ...] = (),
        engine_status: str = "",
        engine_time_s: float = 0.0,
        log: str = "",
    ) -> PlanResult:
        if status in (PlanStatus.UNSOLVABLE, PlanStatus.UNSUPPORTED, PlanStatus.ERROR):
            explanation = _undefined_numbers_first(task, explanation)
        return PlanResult(
            status=status,
            actions=steps or [],
            planner=self._label,
            planning_time_s=time.monotonic() - started,
            explanation=explanation,
            warnings=tuple(dict.fromkeys(notes)),
            unreachable_goals=unreachable_goals,
            engine_status=engine_status,
            engine_time_s=engine_time_s,
            log=log,
        )


_cache_lock = threading.Lock()


def _undefined_numbers_first(task: PlanningTask, explanation: str) -> str:
    """A numeric fluent that is read but has no initial value (the front end's warning)
    is the likely cause of a failure: the reason names it before the engine's words
    (which say "UNDEFINED_INITIAL_NUMERIC", or "no plan exists")."""
    for warning in task.warnings:
        first = warning.splitlines()[0] if warning else ""
        if NO_INITIAL_VALUE in first:
            return f"{first.split(': warning: ', 1)[-1]}; {explanation}"
    return explanation


def _unreachable(task: PlanningTask, timeout: float) -> ReachabilityReport:
    """The delete-relaxation analysis of a "no plan"; nothing is claimed for problems
    it does not model (durative actions: their conditions are split in time)."""
    if any(hasattr(action, "duration") for action in task.problem.actions):
        return ReachabilityReport(complete=False)
    return relaxed_unreachable_goals(task, timeout=timeout)


def _lacking(engine_name: str, task: PlanningTask) -> list[str]:
    """Features of ``task`` the engine ``engine_name`` does not declare support for."""
    ensure_unified_planning()
    from unified_planning.shortcuts import get_environment

    engine = get_environment().factory.engine(engine_name)
    kind = task.problem.kind
    try:
        if engine.supports(kind):
            return []
        return sorted(set(kind.features) - set(engine.supported_kind().features))
    except Exception:  # meta engines need a concrete problem to answer
        return []


def _first_line(text: str) -> str:
    stripped = text.strip()
    return stripped.splitlines()[0] if stripped else ""
