"""The worker side of the planner processes: parse, derive, solve, reply in JSON.

A :class:`~plan_bridge.planning.worker.Worker` starts ``main()`` of this module in a
fresh process (its own session, so a kill takes every process it started) and
writes one JSON request per line; the replies go back one JSON object per line.
The process keeps the last ``BASE_CACHE_SIZE`` parsed problems (see the module
documentation of :mod:`plan_bridge.planning.worker`), so replans do not parse again.

Plans come back as ``[action, [arguments...]]`` for sequential plans and as
``[action, [arguments...], start, duration]`` for the ``TimeTriggeredPlan`` of a
temporal engine (plan time in seconds; ``duration`` is ``None`` for an instantaneous
action of a temporal plan). Engines that ignore UP's ``timeout`` (TAMER, Kairos,
pyperplan) are stopped by the client, which kills this process at the deadline.

The engine ``warm-gbfs`` is not a unified-planning engine: the request is answered
by the warm search (:mod:`plan_bridge.planning.warm`) on the parsed base problem
itself, with the groundings it keeps per base (no derived copy, no working
directory); ``params.budget_s`` bounds its grounding and search.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence
from typing import IO, Any

from plan_bridge.pddl.spec import ProblemSpec
from plan_bridge.planning.kairos_direct import KAIROS, KairosBase, solve_with_kairos
from plan_bridge.planning.warm import WARM, WarmState, solve_warm
from plan_bridge.planning.worker import BASE_CACHE_SIZE

__all__ = ["main", "serve"]


def serve(requests: IO[str], replies: IO[str]) -> None:
    """Answer solve requests (one JSON object per line) until stdin closes."""
    from plan_bridge.pddl.up_runtime import ensure_unified_planning

    ensure_unified_planning()
    from unified_planning.io import PDDLReader  # type: ignore[import-untyped]

    # Build the grammar once: constructing a PDDLReader costs ~50 ms.
    reader = PDDLReader()
    home = os.getcwd()
    replies.write(json.dumps({"ready": True, "pid": os.getpid()}) + "\n")
    replies.flush()
    for line in requests:
        if not line.strip():
            continue
        request = json.loads(line)
        if request.get("op") == "parse":
            reply = _parse_request(reader, request)
            reply["id"] = request["id"]
            replies.write(json.dumps(reply) + "\n")
            replies.flush()
            continue
        try:
            if request.get("workdir"):
                os.chdir(request["workdir"])
            reply = _solve_request(reader, request)
        except Exception as exc:
            reply = {"outcome": "error", "error_type": type(exc).__name__, "message": str(exc)}
        finally:
            os.chdir(home)
        reply["id"] = request["id"]
        replies.write(json.dumps(reply) + "\n")
        replies.flush()


class _Base:
    """A base problem and what deriving problems from it needs.

    A problem read from text is parsed at once (the expensive part a prime does ahead).
    A problem built in memory (a spec) is made into unified-planning's problem only
    when an engine needs it: Kairos reads the text the spec writes, and needs none.
    """

    def __init__(
        self,
        problem: Any,
        domain: str,
        problem_text: str | None,
        spec: ProblemSpec | None,
        read: Callable[[], Any] | None = None,
    ) -> None:
        #: The texts it came from (a built problem: its spec), for Kairos' own reader.
        self.domain_text = domain
        self.problem_text = problem_text
        self.spec = spec
        self.kairos: KairosBase | None = None
        self._source = problem
        self._read = read
        self._problem: Any = None
        self._true_atoms: dict[tuple[str, ...], Any] | None = None
        #: The warm search's compiled actions and groundings of this problem.
        self.warm = WarmState()
        if problem is not None:
            self._up()

    def _up(self) -> Any:
        """The unified-planning problem (made on first use) and what derives from it."""
        if self._problem is None:
            import warnings

            from plan_bridge.pddl.up_runtime import lean_copy

            source = self._source
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the client reported them when it loaded it
                if source is None and self._read is not None:
                    source = self._read()
                elif source is None and self.spec is not None:
                    source = self.spec.build()
            self._problem = lean_copy(source)
            self.kind = self._problem.kind
            # Fact -> fluent expression of the atoms true in the base's initial state.
            self._true_atoms = {
                _atom_of(fluent_exp): fluent_exp
                for fluent_exp, value in self._problem.explicit_initial_values.items()
                if fluent_exp.type.is_bool_type() and value.is_bool_constant() and value.is_true()
            }
            self.goal_atoms = _conjunctive_goal(self._problem.goals)
        return self._problem

    @property
    def problem(self) -> Any:
        return self._up()

    @property
    def true_atoms(self) -> dict[tuple[str, ...], Any]:
        self._up()
        assert self._true_atoms is not None
        return self._true_atoms

    def derive(
        self,
        init: list[list[str]] | None,
        goal: list[list[str]] | None,
        values: list[list[Any]] | None = None,
    ) -> Any:
        """The problem to solve: the base with ``init`` true (all other boolean atoms
        false), ``goal`` as its goal and ``values`` (``[fluent, *args, number]``) as
        the initial values of numeric atoms; the base itself when none changes it."""
        new_init = None if init is None else {tuple(atom) for atom in init}
        new_goal = None if goal is None else sorted({tuple(atom) for atom in goal})
        if new_init is not None and new_init == set(self.true_atoms):
            new_init = None
        if new_goal is not None and new_goal == self.goal_atoms:
            new_goal = None
        if new_init is None and new_goal is None and not values:
            return self.problem
        from plan_bridge.pddl.up_runtime import lean_copy

        # Changing boolean initial values and positive goal atoms does not change the
        # problem kind: keep the base's instead of recomputing it on every replan.
        problem = lean_copy(self.problem, kind=self.kind)
        if new_init is not None:
            for atom, fluent_exp in self.true_atoms.items():
                if atom not in new_init:
                    problem.set_initial_value(fluent_exp, False)
            for atom in new_init:
                if atom not in self.true_atoms:
                    problem.set_initial_value(_expression(problem, atom), True)
        for entry in values or ():
            # Numbers travel as floats; an integer fluent keeps an integer value.
            fluent_exp = _expression(problem, [str(word) for word in entry[:-1]])
            number = entry[-1]
            if fluent_exp.type.is_int_type():
                number = round(number)
            problem.set_initial_value(fluent_exp, _exact(number))
        if new_goal is not None:
            problem.clear_goals()
            for atom in new_goal:
                problem.add_goal(_expression(problem, atom))
        return problem


def _exact(number: float) -> Any:
    """A float as UP wants it: an int, or an exact ``Fraction`` (no binary noise)."""
    from fractions import Fraction

    if float(number).is_integer():
        return int(number)
    return Fraction(str(number))


def _atom_of(fluent_exp: Any) -> tuple[str, ...]:
    return (fluent_exp.fluent().name, *(arg.object().name for arg in fluent_exp.args))


def _expression(problem: Any, atom: Sequence[str]) -> Any:
    return problem.fluent(atom[0])(*(problem.object(name) for name in atom[1:]))


def _conjunctive_goal(goals: Iterable[Any]) -> list[tuple[str, ...]] | None:
    """The goal's atoms, sorted, if it is a conjunction of positive ground atoms."""
    atoms: list[tuple[str, ...]] = []
    pending = list(goals)
    while pending:
        node = pending.pop()
        if node.is_and():
            pending.extend(node.args)
        elif node.is_fluent_exp() and all(arg.is_object_exp() for arg in node.args):
            atoms.append(_atom_of(node))
        elif not node.is_true():
            return None
    return sorted(set(atoms))


_bases: OrderedDict[str, _Base] = OrderedDict()


def _parse_base(reader: Any, request: dict[str, Any], *, eager: bool = True) -> float:
    """Keep the request's base problem in the cache under its key: its text parsed now
    (``eager``: a prime, an engine that needs it) or when first needed, its spec built
    when first needed. The time it took."""
    started = time.monotonic()
    domain = request["domain"]
    if request.get("spec") is not None:
        spec = ProblemSpec.from_json(domain, json.loads(request["spec"]))
        base = _Base(None, domain, None, spec)
    else:
        text = request["problem"]
        base = _Base(
            None, domain, text, None, read=lambda: reader.parse_problem_string(domain, text)
        )
        if eager:
            base._up()  # parsed now
    _bases[request["base"]] = base
    while len(_bases) > BASE_CACHE_SIZE:
        _bases.popitem(last=False)
    return time.monotonic() - started


def _parse_request(reader: Any, request: dict[str, Any]) -> dict[str, Any]:
    if request["base"] in _bases:
        _bases.move_to_end(request["base"])
        return {"outcome": "parsed", "parse_time_s": 0.0}
    # A temporal domain is planned by Kairos first, which reads the text itself: a
    # parse of unified-planning's now would only hold up the first solve.
    eager = ":durative-action" not in request["domain"].lower()
    try:
        return {"outcome": "parsed", "parse_time_s": _parse_base(reader, request, eager=eager)}
    except Exception as exc:
        # The client parses the same text and reports the error properly.
        return {"outcome": "error", "error_type": type(exc).__name__, "message": str(exc)}


def _solve_request(reader: Any, request: dict[str, Any]) -> dict[str, Any]:
    import warnings

    from unified_planning.shortcuts import OneshotPlanner  # type: ignore[import-untyped]

    key = request["base"]
    reused = key in _bases
    parse_time = 0.0
    if not reused:
        if request.get("domain") is None or (
            request.get("problem") is None and request.get("spec") is None
        ):
            return {"outcome": "missing-base"}
        # Kairos reads the text itself: no parse of unified-planning's for it.
        parse_time = _parse_base(reader, request, eager=request["engine"] != KAIROS)
    base = _bases[key]
    _bases.move_to_end(key)
    if request["engine"] == WARM:
        return {**_warm_request(base, request), "parse_time_s": parse_time, "reused": reused}
    if request["engine"] == KAIROS:
        direct = solve_with_kairos(base, request)
        if direct is not None:
            return {**direct, "parse_time_s": parse_time, "reused": reused}
    started = time.monotonic()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            problem = base.derive(request.get("init"), request.get("goal"), request.get("values"))
            with OneshotPlanner(name=request["engine"], params=request.get("params")) as planner:
                result = planner.solve(problem, timeout=request["timeout"])
        except Exception as exc:
            return {
                "outcome": "error",
                "error_type": type(exc).__name__,
                "message": str(exc),
                "warnings": [str(w.message) for w in caught],
                "engine_time_s": time.monotonic() - started,
                "parse_time_s": parse_time,
            }
    plan = [] if result.plan is None else _plan_entries(result.plan)
    log = "\n".join(m.message for m in (result.log_messages or []) if m.message.strip())
    return {
        "outcome": "result",
        "status": result.status.name,
        "plan": plan,
        "warnings": [str(w.message) for w in caught],
        "log": log[-4000:],
        "engine_time_s": time.monotonic() - started,
        "parse_time_s": parse_time,
        "reused": reused,
    }


def _warm_request(base: _Base, request: dict[str, Any]) -> dict[str, Any]:
    """Plan with the warm search on the base problem itself (no derived copy)."""
    init = request.get("init")
    goal = request.get("goal")
    if request.get("values"):
        return {"outcome": "result", "status": "UNSUPPORTED_PROBLEM", "message": "numbers"}
    state = base.true_atoms.keys() if init is None else (tuple(atom) for atom in init)
    atoms = None if goal is None else [tuple(atom) for atom in goal]
    # The budget counts from now (the problem is parsed), within the hard time limit.
    limit = request.get("timeout")
    budget = (request.get("params") or {}).get("budget_s")
    if budget is not None:
        limit = budget if limit is None else min(limit, budget)
    return solve_warm(base.problem, base.warm, state, atoms, limit)


def _plan_entries(plan: Any) -> list[list[Any]]:
    """A UP plan as JSON lists: ``[name, args]``, or ``[name, args, start, duration]``
    for a time-triggered plan (UP's ``Fraction`` times as floats)."""

    def names(instance: Any) -> list[str]:
        return [arg.object().name for arg in instance.actual_parameters]

    timed = getattr(plan, "timed_actions", None)
    if timed is None:
        return [[instance.action.name, names(instance)] for instance in plan.actions]
    return [
        [
            instance.action.name,
            names(instance),
            float(start),
            None if duration is None else float(duration),
        ]
        for start, instance, duration in sorted(timed, key=lambda entry: float(entry[0]))
    ]


def main() -> None:
    # Our replies own the real stdout; anything an engine prints goes to stderr.
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "w", encoding="utf-8")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    serve(sys.stdin, replies)


if __name__ == "__main__":
    main()
