"""The warm planning path, worker side: plan in the worker, without a new process.

A planner worker (:mod:`plan_bridge.planning.service`) answers requests for the
engine :data:`WARM` itself instead of through unified-planning: it compiles the
base problem's actions once (:class:`~plan_bridge.planning.grounding.LiftedModel`),
grounds them from the request's state (or reuses a grounding that covers it: a
replan usually changes a few fluent atoms) and runs the greedy search of
:mod:`plan_bridge.planning.search` within the request's time limit.

Every plan is checked before it is sent: each step is simulated on the problem's
own action definitions (unified-planning expressions, read independently of the
grounding: argument types, preconditions, effects) and the goal must hold at the
end. A plan that fails the check is not sent; the reply says why, and the client
falls back to Fast Downward.

Replies have the shape of the unified-planning path's (``status`` is a UP
``PlanGenerationResultStatus`` name): ``SOLVED_SATISFICING``, ``UNSOLVABLE_PROVEN``
(relaxed reachability or an exhausted search), ``TIMEOUT`` (the budget was spent)
or ``UNSUPPORTED_PROBLEM`` (a construct the warm search does not handle, too many
ground actions, or a plan that failed its check).
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from collections.abc import Iterable, Sequence
from typing import Any

from plan_bridge.planning.grounding import (
    Atom,
    GroundTask,
    LiftedModel,
    Operator,
    UnsupportedProblemError,
)
from plan_bridge.planning.search import greedy_search

__all__ = ["MAX_OPERATORS", "WARM", "WarmState", "solve_warm"]

#: The engine name of the warm search.
WARM = "warm-gbfs"
#: Ground actions beyond which a problem is left to Fast Downward.
MAX_OPERATORS = 5000
#: Groundings kept per base problem (each covers the states it was made for).
GROUNDINGS_KEPT = 4


class WarmState:
    """What the warm search keeps per base problem in a worker."""

    def __init__(self) -> None:
        #: Held by a caller that shares this state between threads.
        self.lock = threading.Lock()
        self.model: LiftedModel | None = None
        self.unsupported = ""
        self.groundings: OrderedDict[int, GroundTask] = OrderedDict()
        self._next = 0

    def lifted(self, problem: Any) -> LiftedModel:
        if self.model is None and not self.unsupported:
            try:
                self.model = LiftedModel(problem)
            except UnsupportedProblemError as exc:
                self.unsupported = str(exc)
        if self.model is None:
            raise UnsupportedProblemError(self.unsupported)
        return self.model

    def grounding(self, model: LiftedModel, state: frozenset[Atom], deadline: float) -> GroundTask:
        """A grounding that covers ``state`` (reused, or made and kept)."""
        for key, task in self.groundings.items():
            if task.covers(state):
                self.groundings.move_to_end(key)
                return task
        task = model.ground(state, max_operators=MAX_OPERATORS, deadline=deadline)
        self._next += 1
        self.groundings[self._next] = task
        while len(self.groundings) > GROUNDINGS_KEPT:
            self.groundings.popitem(last=False)
        return task


def solve_warm(
    problem: Any,
    cache: WarmState,
    state: Iterable[Atom],
    goal: Sequence[Atom] | None,
    timeout: float | None,
) -> dict[str, Any]:
    """Plan from ``state`` (true atoms) to ``goal`` (positive atoms; None: the
    problem's goal) on the base ``problem``; a reply for the client."""
    started = time.monotonic()
    deadline = started + (timeout if timeout is not None else 60.0)
    atoms = frozenset(state)
    try:
        model = cache.lifted(problem)
        grounded = len(cache.groundings)
        task = cache.grounding(model, atoms, deadline)
        reused = len(cache.groundings) == grounded
    except UnsupportedProblemError as exc:
        return _reply(started, "UNSUPPORTED_PROBLEM", message=f"{WARM}: {exc}")
    positive = model.goal_positive if goal is None else tuple(goal)
    negative = model.goal_negative if goal is None else ()
    masks = task.goal(positive, negative)
    log = f"{len(task.operators)} ground actions ({'reused' if reused else 'grounded'})"
    if masks is None:
        return _reply(started, "UNSOLVABLE_PROVEN", log=f"{log}; a goal atom is unreachable")
    outcome = greedy_search(task, task.bits(atoms), masks, deadline=deadline)
    log += f"; {outcome.expansions} expansions, {outcome.evaluations} evaluations"
    if outcome.status == "unsolvable":
        return _reply(started, "UNSOLVABLE_PROVEN", log=log)
    if outcome.status == "budget":
        return _reply(started, "TIMEOUT", log=log, message=f"{WARM}: search budget spent")
    problem_goal = None if goal is not None else problem.goals
    try:
        flaw = check_plan(problem, outcome.plan, atoms, goal, problem_goal)
    except UnsupportedProblemError as exc:
        flaw = str(exc)
    if flaw:
        return _reply(started, "UNSUPPORTED_PROBLEM", log=log, message=f"{WARM}: {flaw}")
    plan = [[op.name, list(op.arguments)] for op in outcome.plan]
    return _reply(started, "SOLVED_SATISFICING", log=log, plan=plan)


def _reply(
    started: float,
    status: str,
    *,
    log: str = "",
    message: str = "",
    plan: list[list[Any]] | None = None,
) -> dict[str, Any]:
    return {
        "outcome": "result",
        "status": status,
        "plan": plan or [],
        "warnings": [],
        "log": log,
        "message": message,
        "engine_time_s": time.monotonic() - started,
    }


# -- the independent plan check ------------------------------------------------
def check_plan(
    problem: Any,
    plan: Sequence[Operator],
    state: frozenset[Atom],
    goal: Sequence[Atom] | None,
    problem_goal: Sequence[Any] | None,
) -> str:
    """Why ``plan`` is not a plan from ``state`` (empty when it is one): simulated on
    ``problem``'s action definitions, then ``goal`` (atoms) or ``problem_goal``
    (UP expressions) evaluated."""
    facts = set(state)
    for number, op in enumerate(plan, 1):
        action = problem.action(op.name)
        parameters = action.parameters
        if len(parameters) != len(op.arguments):
            return f"step {number} ({op.name}) has the wrong number of arguments"
        binding: dict[str, str] = {}
        for parameter, name in zip(parameters, op.arguments, strict=True):
            if not problem.has_object(name) or not _is_a(problem.object(name).type, parameter.type):
                return f"step {number} ({op.name}): {name} is not a {parameter.type}"
            binding[parameter.name] = name
        if not all(_holds(node, binding, facts) for node in action.preconditions):
            return f"step {number} ({op.name} {' '.join(op.arguments)}) is not applicable"
        adds: set[Atom] = set()
        deletes: set[Atom] = set()
        for effect in action.effects:
            if not effect.fluent.type.is_bool_type():
                continue  # costs
            atom = _atom(effect.fluent, binding)
            (adds if effect.value.bool_constant_value() else deletes).add(atom)
        facts -= deletes
        facts |= adds
    if goal is not None:
        missing = [a for a in goal if a not in facts]
        return f"the goal atom {missing[0]} does not hold at the end" if missing else ""
    if not all(_holds(node, {}, facts) for node in problem_goal or ()):
        return "the goal does not hold at the end"
    return ""


def _is_a(object_type: Any, wanted: Any) -> bool:
    current = object_type
    while current is not None:
        if current == wanted:
            return True
        current = current.father
    return False


def _name(node: Any, binding: dict[str, str]) -> str:
    if node.is_parameter_exp():
        return binding[node.parameter().name]
    return str(node.object().name)


def _atom(node: Any, binding: dict[str, str]) -> Atom:
    return (node.fluent().name, *(_name(arg, binding) for arg in node.args))


def _holds(node: Any, binding: dict[str, str], facts: set[Atom]) -> bool:
    if node.is_and():
        return all(_holds(arg, binding, facts) for arg in node.args)
    if node.is_not():
        return not _holds(node.arg(0), binding, facts)
    if node.is_bool_constant():
        return bool(node.bool_constant_value())
    if node.is_equals():
        return _name(node.arg(0), binding) == _name(node.arg(1), binding)
    if node.is_fluent_exp():
        return _atom(node, binding) in facts
    raise UnsupportedProblemError(f"cannot check the condition {node}")
