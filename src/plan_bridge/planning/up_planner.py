"""A unified-planning one-shot engine behind the :class:`~plan_bridge.planning.types.Planner`
protocol (:class:`UPPlanner`), each solve in a killable worker process, and which of
those engines are installed.

"No plan" is a :class:`~plan_bridge.planning.types.PlanResult`, never an exception:
its ``status`` says what happened (unsolvable, timeout, unsupported, error) and
``explanation`` says why, e.g. the goal atoms that are unreachable even under delete
relaxation.

Every solve runs in a warm worker process (:mod:`plan_bridge.planning.worker`) that is
killed at the deadline, so ``timeout`` holds for engines that ignore it. Planners by
name are :func:`~plan_bridge.planning.registry.get_planner`'s; engine choice is
:mod:`.engines`.
"""

from __future__ import annotations

import dataclasses
import threading
import time
import weakref
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from plan_bridge.errors import PlannerNotFoundError
from plan_bridge.pddl.initial_values import NO_INITIAL_VALUE
from plan_bridge.pddl.reachability import ReachabilityReport, relaxed_unreachable_goals
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask
from plan_bridge.pddl.up_runtime import ensure_unified_planning
from plan_bridge.planning.problem_source import problem_source as _problem_source
from plan_bridge.planning.types import PlanResult, PlanStatus, PlanStep, snapshot_values
from plan_bridge.planning.worker import ProblemText, SolveReply, WorkerPool, default_pool

__all__ = [
    "DEFAULT_PLANNER",
    "SolveRequest",
    "UPPlanner",
    "installed_planners",
    "oneshot_planners",
    "up_kind",
]

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


# Engines that warn they ignore UP's timeout: the worker kill enforces it anyway,
# so the warning is noise for our users.
_IGNORED_WARNINGS = ("does not support timeout",)


@dataclass(frozen=True)
class SolveRequest:
    """What a solve asks of an engine besides the base problem: its true initial atoms,
    goal atoms and numeric values (``[fluent, *args, number]``), in the PDDL text's
    names; None keeps the base problem's."""

    init: list[list[str]] | None = None
    goal: list[list[str]] | None = None
    values: list[list[Any]] | None = None


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

    #: Whether the engine writes files (each solve then gets a working directory).
    needs_workdir = True

    def __init__(
        self,
        engine: str = DEFAULT_PLANNER,
        *,
        pool: WorkerPool | None = None,
        explain_timeout: float = 5.0,
        params: Mapping[str, Any] | None = None,
        label: str | None = None,
    ) -> None:
        self._check_engine(engine)
        self._engine = engine
        self.params = dict(params or {})
        self._label = label or engine
        self._pool = pool
        self.explain_timeout = explain_timeout
        self._unsupported: weakref.WeakKeyDictionary[PlanningTask, list[str]] = (
            weakref.WeakKeyDictionary()
        )

    @staticmethod
    def _check_engine(engine: str) -> None:
        available = oneshot_planners()
        if engine not in available:
            raise PlannerNotFoundError(engine, [n for n in available if "[" not in n])

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
        kind = up_kind(task)
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
        values = snapshot_values(initial_state, values)
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
        request = SolveRequest(
            init=None if facts is None else [source.pddl_atom(f) for f in sorted(facts)],
            goal=None if goal_atoms is None else [source.pddl_atom(a) for a in goal_atoms],
            values=None
            if not values
            else [[*source.pddl_atom(atom), float(v)] for atom, v in sorted(values.items())],
        )
        reply = self._solve_here(task, source.text, request, timeout)
        if reply is None:
            with self.pool.worker(prefer=source.text.key) as worker:
                reply = worker.solve(
                    self._engine,
                    source.text,
                    timeout,
                    init=request.init,
                    goal=request.goal,
                    values=request.values,
                    params=self.params,
                    cancel=cancel,
                    workdir=self.needs_workdir,
                )
        if reply.outcome == "cancelled":
            return self._finish(
                view, started, PlanStatus.TIMEOUT, f"{self.name}: {reply.message}", notes
            )
        notes.extend(w for w in reply.warnings if not any(i in w for i in _IGNORED_WARNINGS))
        result = self._interpret(view, started, timeout, reply, source.writer, notes, missing)
        return dataclasses.replace(result, problem_reused=True) if reply.reused else result

    def _solve_here(
        self, task: PlanningTask, text: ProblemText, request: SolveRequest, timeout: float
    ) -> SolveReply | None:
        """A reply computed in this process instead of a worker (None: use a worker).
        Engines run in workers; the warm search overrides this for cold starts."""
        return None

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
                reply=reply,
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
                reply=reply,
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
                reply=reply,
            )
        kind = f"{reply.error_type}: " if reply.error_type else ""
        return self._finish(
            task,
            started,
            PlanStatus.ERROR,
            f"{self._engine} failed: {kind}{_first_line(message)}",
            notes,
            reply=reply,
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
            reply=reply,
            engine_status=reply.status or reply.outcome.upper(),
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
        reply: SolveReply | None = None,
        engine_status: str | None = None,
    ) -> PlanResult:
        """The result; ``reply`` gives the engine's status (unless ``engine_status``),
        time and log."""
        if status in (PlanStatus.UNSOLVABLE, PlanStatus.UNSUPPORTED, PlanStatus.ERROR):
            explanation = _undefined_numbers_first(task, explanation)
        if engine_status is None:
            engine_status = "" if reply is None else reply.status
        return PlanResult(
            status=status,
            actions=steps or [],
            planner=self._label,
            planning_time_s=time.monotonic() - started,
            explanation=explanation,
            warnings=tuple(dict.fromkeys(notes)),
            unreachable_goals=unreachable_goals,
            engine_status=engine_status,
            engine_time_s=0.0 if reply is None else reply.engine_time_s,
            log="" if reply is None else reply.log,
        )


_cache_lock = threading.Lock()
_up_kinds: weakref.WeakKeyDictionary[PlanningTask, Any] = weakref.WeakKeyDictionary()


def up_kind(task: PlanningTask) -> Any:
    """unified-planning's ``ProblemKind`` of ``task``, computed once per task (UP
    recomputes it on every access: up to ~0.2 s on large problems)."""
    with _cache_lock:
        kind = _up_kinds.get(task)
    if kind is None:
        ensure_unified_planning()
        kind = task.problem.kind
        with _cache_lock:
            _up_kinds[task] = kind
    return kind


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
    kind = up_kind(task)
    try:
        if engine.supports(kind):
            return []
        return sorted(set(kind.features) - set(engine.supported_kind().features))
    except Exception:  # meta engines need a concrete problem to answer
        return []


def _first_line(text: str) -> str:
    stripped = text.strip()
    return stripped.splitlines()[0] if stripped else ""
