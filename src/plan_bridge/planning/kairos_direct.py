"""Kairos without unified-planning's round trip, in the planner worker.

Through unified-planning, a Kairos solve writes the problem back to PDDL with UP's
writer (``KairosWriter``), computes UP's problem kind several times and corrects the
plan's times with UP's expressions: on a small temporal problem that is about 90 ms
around a search of 8 ms. Kairos reads PDDL itself, natively and in well under a
millisecond, so the worker hands it text directly:

* a problem read from PDDL: the very text that was read, its ``(:init ...)`` and
  ``(:goal ...)`` restated for the request's state and goal
  (:func:`~plan_bridge.pddl.source.replace_init`);
* a problem plan_bridge built (a :class:`~plan_bridge.pddl.spec.ProblemSpec`): the
  text the spec writes for the request's state and goal.

The domain is parsed once per base problem. Anything Kairos does not read (a
construct of the text it refuses) falls back to the unified-planning path, for that
base from then on. Replies have the shape of the unified-planning path's.
"""

from __future__ import annotations

import queue
import re
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from plan_bridge.pddl.restate import replace_init
from plan_bridge.pddl.source import SourceText
from plan_bridge.pddl.spec import ProblemSpec

__all__ = ["KAIROS", "KairosBase", "solve_with_kairos"]

#: The engine name this path answers for.
KAIROS = "kairos"
#: Options of a request's ``params`` that go to Kairos' search as they are.
_OPTIONS = ("search", "seed", "threads", "memory_limit_mb", "stop_after_no_improvement")
_DURATIVE = re.compile(r"\(\s*:durative-action\s+([^\s()]+)", re.IGNORECASE)
_NO_KAIROS_TIMEOUT_S = 3600.0
#: The share of a solve's time (and the most seconds) a problem's preset search gets.
_PRESET_SHARE = 0.3
_PRESET_MAX_S = 2.0


class KairosBase:
    """Kairos' parse of a base problem's domain (or why Kairos cannot read it)."""

    def __init__(self, domain: Any, durative: frozenset[str], refused: str = "") -> None:
        self.domain = domain
        self.durative = durative
        self.refused = refused


class _Source(Protocol):
    """What the worker keeps of a base problem (``service._Base``)."""

    domain_text: str
    problem_text: str | None
    spec: ProblemSpec | None
    kairos: KairosBase | None

    @property
    def true_atoms(self) -> dict[tuple[str, ...], Any]: ...


def solve_with_kairos(base: _Source, request: dict[str, Any]) -> dict[str, Any] | None:
    """Kairos' reply to ``request`` on ``base``, or None when this path cannot serve
    it (Kairos is not installed or does not read the text): then unified-planning's."""
    try:
        import kairos
    except ImportError:
        return None
    if base.kairos is None:
        try:
            domain = kairos.parse_domain(base.domain_text, "domain.pddl")
            names = frozenset(n.lower() for n in _DURATIVE.findall(base.domain_text))
            base.kairos = KairosBase(domain, names)
        except kairos.PddlError as exc:
            base.kairos = KairosBase(None, frozenset(), str(exc))
    if base.kairos.refused:
        return None
    text = _problem_text(base, request)
    if text is None:
        return None
    started = time.monotonic()
    try:
        problem = kairos.parse_problem(text, base.kairos.domain, "problem.pddl")
    except kairos.PddlError:
        return None
    limit = request.get("timeout")
    deadline = started + (float(limit) if limit is not None else _NO_KAIROS_TIMEOUT_S)
    params = dict(request.get("params") or {})
    spec = base.spec
    window = spec.improve_s if spec is not None else 0.0
    # A problem built with a metric but no time to improve plans: the first plan.
    anytime = None if spec is None or window > 0 else False
    preset = spec.search if spec is not None and "search" not in params else ""
    if preset:
        # The preset that suits this kind of problem first, on a share of the time;
        # Kairos' own choice after it, if it finds no plan.
        share = min(_PRESET_SHARE * (deadline - started), _PRESET_MAX_S)
        options = _options(kairos, text, params, preset, share, anytime)
        found = _search(kairos, problem, options, window, started + share)
        if found.plan is not None or found.status == "UNSOLVABLE":
            return _reply(found, base.kairos.durative, time.monotonic() - started)
        problem = kairos.parse_problem(text, base.kairos.domain, "problem.pddl")
    left = max(0.001, deadline - time.monotonic())
    options = _options(kairos, text, params, "", left, anytime)
    found = _search(kairos, problem, options, window, deadline)
    return _reply(found, base.kairos.durative, time.monotonic() - started)


@dataclass(frozen=True)
class _Found:
    """What a search ended with: Kairos' status name, the best plan, the stop reason."""

    status: str
    plan: Any
    optimal: bool
    diagnostics: tuple[Any, ...] = ()


def _search(kairos: Any, problem: Any, options: Any, window: float, deadline: float) -> _Found:
    """Kairos' search; with ``window`` > 0 and a metric, it is stopped once ``window``
    seconds pass without a better plan (Kairos' own ``stop_after_no_improvement`` is
    not honoured by its planner), else it runs to its end or time limit."""
    planner = kairos.Planner()
    start = getattr(getattr(planner, "_planner", None), "start", None)
    if window <= 0 or not options.anytime or start is None:
        result = planner.solve(problem, options)
        return _Found(
            result.status.name,
            result.plan,
            result.stop_reason == kairos.StopReason.PROVEN_OPTIMAL,
            tuple(result.diagnostics),
        )
    search = start(problem, options, None, None)
    plans: queue.Queue[Any] = queue.Queue()

    def collect() -> None:
        try:
            for plan in search.plans():
                plans.put(plan)
        finally:
            plans.put(None)

    threading.Thread(target=collect, name="kairos-plans", daemon=True).start()
    best: Any = None
    ended = False
    while True:
        wait = deadline - time.monotonic()
        if best is not None:
            wait = min(wait, window)
        if wait <= 0:
            break
        try:
            plan = plans.get(timeout=wait)
        except queue.Empty:
            break
        if plan is None:
            ended = True
            break
        best = plan
    search.stop()
    result = search.wait()
    if best is None:
        best = result.plan
    optimal = ended and result.stop_reason == kairos.StopReason.PROVEN_OPTIMAL
    status = "SOLVED" if best is not None else result.status.name
    return _Found(status, best, optimal, tuple(result.diagnostics))


def _options(
    kairos: Any,
    text: str,
    params: dict[str, Any],
    search: str,
    seconds: float,
    anytime: bool | None = None,
) -> Any:
    options = kairos.SearchOptions()
    options.timeout = seconds
    # As UP's Kairos engine does: improve a plan only when a metric says what is better.
    options.anytime = ":metric" in text.lower() if anytime is None else anytime
    for name, value in params.items():
        if name in _OPTIONS:
            setattr(options, name, value)
    if search:
        options.search = search
    return options


def _problem_text(base: _Source, request: dict[str, Any]) -> str | None:
    """The problem's text for the request's initial state and goal."""
    init = request.get("init")
    goal = request.get("goal")
    values = {
        tuple(str(w).lower() for w in entry[:-1]): float(entry[-1])
        for entry in request.get("values") or ()
    }
    facts = None if init is None else [tuple(str(w) for w in atom) for atom in init]
    atoms = None if goal is None else [tuple(str(w) for w in atom) for atom in goal]
    if base.spec is not None:
        return base.spec.with_state(init=facts, values=values, goal=atoms).pddl_text()
    if base.problem_text is None:
        return None
    if facts is None and atoms is None and not values:
        return base.problem_text
    source = SourceText(base.problem_text, "problem.pddl", "problem")
    return replace_init(
        source, facts if facts is not None else sorted(base.true_atoms), values, atoms
    )


def _reply(found: _Found, durative: frozenset[str], seconds: float) -> dict[str, Any]:
    status = _STATUS.get(found.status, "INTERNAL_ERROR")
    plan: list[list[Any]] = []
    if found.plan is not None:
        status = "SOLVED_OPTIMALLY" if found.optimal else "SOLVED_SATISFICING"
        plan = [_entry(step, found.plan.temporal, durative) for step in found.plan.steps]
    messages = [str(d) for d in found.diagnostics]
    return {
        "outcome": "result",
        "status": status,
        "plan": plan,
        "warnings": [],
        "log": "\n".join(messages)[-4000:],
        "engine_time_s": seconds,
    }


def _entry(step: Any, temporal: bool, durative: frozenset[str]) -> list[Any]:
    name = str(step.name).lower()
    args: Sequence[str] = [str(a).lower() for a in step.args]
    if not temporal:
        return [name, list(args)]
    duration = float(step.duration) if name in durative else None
    return [name, list(args), float(step.time), duration]


#: Kairos' statuses without a plan, as unified-planning's result statuses.
_STATUS = {
    "SOLVED": "SOLVED_SATISFICING",
    "UNSOLVABLE": "UNSOLVABLE_PROVEN",
    "NO_PLAN_FOUND": "UNSOLVABLE_INCOMPLETELY",
    "TIMEOUT": "TIMEOUT",
    "CANCELLED": "TIMEOUT",
    "OUT_OF_MEMORY": "MEMOUT",
    "GROUNDING_TOO_LARGE": "MEMOUT",
    "UNSUPPORTED": "UNSUPPORTED_PROBLEM",
    "INVALID_INPUT": "INTERNAL_ERROR",
    "INTERNAL_ERROR": "INTERNAL_ERROR",
}
