"""Plans remembered per (task, state, goal): a replan from a state seen before costs
nothing.

A deterministic planner gives the same plan for the same (state, goal), so asking it
again is wasted time: a mission that comes back to a state it planned from, a study
that runs the same problem with many seeds, a repair that asks for the same facts
again. Only found plans are remembered (a timeout may not repeat), and the
executive checks a remembered plan against the belief before using it.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Iterable, Sequence

from plan_bridge.pddl.source import ProblemText
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.planning.types import PlanStep

__all__ = ["PlanCache"]

_Key = tuple[str, frozenset[Fact], frozenset[Fact] | None]


class PlanCache:
    """A bounded, thread-safe map (task, state, goal) -> plan; share one between
    executives to reuse plans across missions of the same problem."""

    def __init__(self, max_entries: int = 256) -> None:
        if max_entries < 1:
            raise ValueError(f"max_entries must be >= 1, got {max_entries}")
        self.max_entries = max_entries
        self._plans: OrderedDict[_Key, tuple[tuple[PlanStep, ...], str]] = OrderedDict()
        self._lock = threading.Lock()
        # Tasks built in code have no text: they are told apart by identity, and kept
        # alive here so that their id is not reused by another task.
        self._anonymous: dict[int, PlanningTask] = {}
        self.hits = 0
        self.misses = 0

    def __len__(self) -> int:
        with self._lock:
            return len(self._plans)

    def _key(self, task: PlanningTask, state: Iterable[Fact], goal: Iterable[Fact] | None) -> _Key:
        if task.domain_text is not None and task.problem_text is not None:
            name = ProblemText.of(task.domain_text, task.problem_text).key
        elif task.spec is not None:
            name = f"spec:{task.spec.key}"
        else:
            self._anonymous[id(task)] = task
            name = f"object:{id(task)}"
        return (name, frozenset(state), None if goal is None else frozenset(goal))

    def get(
        self, task: PlanningTask, state: Iterable[Fact], goal: Iterable[Fact] | None = None
    ) -> tuple[list[PlanStep], str] | None:
        """The plan remembered for this (task, state, goal) and the planner that found
        it, or None."""
        with self._lock:
            key = self._key(task, state, goal)
            entry = self._plans.get(key)
            if entry is None:
                self.misses += 1
                return None
            self._plans.move_to_end(key)
            self.hits += 1
            return list(entry[0]), entry[1]

    def put(
        self,
        task: PlanningTask,
        state: Iterable[Fact],
        goal: Iterable[Fact] | None,
        plan: Sequence[PlanStep],
        planner: str = "",
    ) -> None:
        with self._lock:
            key = self._key(task, state, goal)
            self._plans[key] = (tuple(plan), planner)
            self._plans.move_to_end(key)
            while len(self._plans) > self.max_entries:
                self._plans.popitem(last=False)
            live = {k[0] for k in self._plans}
            self._anonymous = {i: t for i, t in self._anonymous.items() if f"object:{i}" in live}

    def clear(self) -> None:
        with self._lock:
            self._plans.clear()
            self._anonymous.clear()
