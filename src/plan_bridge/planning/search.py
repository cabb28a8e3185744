"""The warm search: lazy greedy best-first search with the FF heuristic.

Runs in the planner worker on a :class:`~plan_bridge.planning.grounding.GroundTask`
(states are integers, one bit per fluent atom). It is the search Fast Downward's
``lazy_greedy([ff], preferred=[ff])`` does, written small: a state's heuristic value
is computed when it is expanded, its successors wait in an open list ordered by it,
and the successors through *preferred* operators (the operators of the relaxed plan
that apply) wait in a second open list that is tried first after each progress.

States whose relaxed plan does not exist are dead ends (pruned: sound). When both
open lists run empty, every reachable state was closed or pruned, so the search is a
proof that no plan exists. The search stops at its deadline or expansion limit and
then says so (``budget``): the caller hands the problem to Fast Downward.
"""

from __future__ import annotations

import heapq
import itertools
import time
from dataclasses import dataclass

from plan_bridge.planning.grounding import GroundTask, Operator

__all__ = ["SearchOutcome", "eliminate_redundant_actions", "greedy_search"]

_INFINITY = 1 << 30
#: Preferred-list boost after progress (Fast Downward's default).
_BOOST = 1000


@dataclass(frozen=True)
class SearchOutcome:
    """What a search ended with."""

    status: str
    """``solved``, ``unsolvable`` (proof) or ``budget`` (deadline or limit reached)."""
    plan: tuple[Operator, ...] = ()
    expansions: int = 0
    evaluations: int = 0


class _Heuristic:
    """h_FF (the size of a relaxed plan built from h_add supporters) and preferred
    operators, evaluated on bit-mask states."""

    def __init__(self, task: GroundTask, goal: int) -> None:
        self.operators = task.operators
        self.size = len(task.facts)
        self.goal_facts = [bit for bit in range(self.size) if goal >> bit & 1]
        self.pre_count = [len(op.pre_facts) for op in task.operators]
        self.users: list[list[int]] = [[] for _ in range(self.size)]
        for number, op in enumerate(task.operators):
            for bit in op.pre_facts:
                self.users[bit].append(number)
        self.free = [n for n, op in enumerate(task.operators) if not op.pre_facts]

    def evaluate(self, state: int) -> tuple[int, list[int]]:
        """(h_FF of ``state`` or ``_INFINITY``, the relaxed plan's operators)."""
        cost = [_INFINITY] * self.size
        supporter = [-1] * self.size
        heap: list[tuple[int, int]] = []
        bits = state
        while bits:
            low = bits & -bits
            bit = low.bit_length() - 1
            cost[bit] = 0
            heap.append((0, bit))
            bits ^= low
        unsatisfied = list(self.pre_count)
        op_cost = [0] * len(self.operators)
        for number in self.free:
            self._fire(number, 1, cost, supporter, heap)
        heapq.heapify(heap)
        goals_left = {bit for bit in self.goal_facts if cost[bit] != 0}
        users = self.users
        while heap and goals_left:
            value, bit = heapq.heappop(heap)
            if value > cost[bit]:
                continue
            goals_left.discard(bit)
            for number in users[bit]:
                unsatisfied[number] -= 1
                op_cost[number] += value
                if unsatisfied[number] == 0:
                    self._fire(number, op_cost[number] + 1, cost, supporter, heap)
        if goals_left:
            return _INFINITY, []
        return self._relaxed_plan(cost, supporter)

    def _fire(
        self,
        number: int,
        value: int,
        cost: list[int],
        supporter: list[int],
        heap: list[tuple[int, int]],
    ) -> None:
        for bit in self.operators[number].add_facts:
            if value < cost[bit]:
                cost[bit] = value
                supporter[bit] = number
                heapq.heappush(heap, (value, bit))

    def _relaxed_plan(self, cost: list[int], supporter: list[int]) -> tuple[int, list[int]]:
        marked: set[int] = set()
        pending = [bit for bit in self.goal_facts if cost[bit] != 0]
        seen: set[int] = set()
        while pending:
            bit = pending.pop()
            if bit in seen:
                continue
            seen.add(bit)
            number = supporter[bit]
            if number not in marked:
                marked.add(number)
                pending.extend(b for b in self.operators[number].pre_facts if cost[b] != 0)
        return len(marked), sorted(marked)


def greedy_search(
    task: GroundTask,
    init: int,
    goal: tuple[int, int],
    *,
    deadline: float,
    max_expansions: int = 200_000,
) -> SearchOutcome:
    """A plan from ``init`` to a state with every bit of ``goal[0]`` set and none of
    ``goal[1]``, or a proof that there is none, or ``budget``."""
    must, must_not = goal
    operators = task.operators
    heuristic = _Heuristic(task, must)
    parents: dict[int, tuple[int, int] | None] = {init: None}
    h_init, preferred = heuristic.evaluate(init)
    if h_init >= _INFINITY:
        return SearchOutcome("unsolvable", evaluations=1)
    queues: tuple[list[tuple[int, int, int, int]], list[tuple[int, int, int, int]]] = ([], [])
    priority = [0, 0]
    order = itertools.count()
    best = h_init
    expansions, evaluations = 0, 1
    state, h = init, h_init
    while True:
        if state & must == must and not state & must_not:
            plan = eliminate_redundant_actions(_plan(parents, operators, state), init, goal)
            return SearchOutcome("solved", plan, expansions, evaluations)
        expansions += 1
        preferred_set = set(preferred)
        for number, op in enumerate(operators):
            if state & op.pre == op.pre and not state & op.neg:
                entry = (h, next(order), state, number)
                heapq.heappush(queues[0], entry)
                if number in preferred_set:
                    heapq.heappush(queues[1], entry)
        if expansions >= max_expansions or time.monotonic() > deadline:
            return SearchOutcome("budget", (), expansions, evaluations)
        while True:
            picked = _pick(queues, priority)
            if picked is None:
                return SearchOutcome("unsolvable", (), expansions, evaluations)
            _, _, parent, number = picked
            op = operators[number]
            state = (parent & ~op.delete) | op.add
            if state in parents:
                continue
            parents[state] = (parent, number)
            evaluations += 1
            h, preferred = heuristic.evaluate(state)
            if h < _INFINITY:
                break
            if time.monotonic() > deadline:  # a run of dead ends
                return SearchOutcome("budget", (), expansions, evaluations)
        if h < best:
            best = h
            priority[1] -= _BOOST


def _pick(
    queues: tuple[list[tuple[int, int, int, int]], list[tuple[int, int, int, int]]],
    priority: list[int],
) -> tuple[int, int, int, int] | None:
    """Pop from the open list with the lowest priority value (alternation)."""
    candidates = [i for i in (1, 0) if queues[i]]
    if not candidates:
        return None
    chosen = min(candidates, key=lambda i: priority[i])
    priority[chosen] += 1
    return heapq.heappop(queues[chosen])


def _plan(
    parents: dict[int, tuple[int, int] | None], operators: tuple[Operator, ...], state: int
) -> tuple[Operator, ...]:
    steps: list[Operator] = []
    link = parents[state]
    while link is not None:
        parent, number = link
        steps.append(operators[number])
        link = parents[parent]
    steps.reverse()
    return tuple(steps)


def eliminate_redundant_actions(
    plan: tuple[Operator, ...], init: int, goal: tuple[int, int]
) -> tuple[Operator, ...]:
    """``plan`` without the actions it does not need (greedy action elimination).

    Greedy search finds plans with detours (a move there and back, a pick whose object
    is put down again). For each action in turn: drop it, and every later action that
    no longer applies; if the goal still holds at the end, keep the shorter plan.
    """
    must, must_not = goal
    index = 0
    while index < len(plan):
        state = init
        kept: list[Operator] = []
        for number, op in enumerate(plan):
            if number == index or state & op.pre != op.pre or state & op.neg:
                continue
            state = (state & ~op.delete) | op.add
            kept.append(op)
        if state & must == must and not state & must_not:
            plan = tuple(kept)
        else:
            index += 1
    return plan
