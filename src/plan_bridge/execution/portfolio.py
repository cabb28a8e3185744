"""A portfolio of planners: several configurations race within one deadline.

Greedy searches can lose themselves from a state where another configuration finds
a plan at once (on blocks probBLOCKS-14-0, Fast Downward's ``lama-first`` takes 0.55 s
and ``add-wastar`` 0.17 s, here). A :class:`PlannerPortfolio` runs up to ``parallel``
members at a time (one per core by default), each in its own worker process; the
first plan wins and the others are cancelled (their processes killed). A member that
ends without a plan frees its slot for the next member. Each member gets an equal
share of what is left of the deadline, so a member that hangs cannot starve the
others.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Iterable, Mapping, Sequence

from plan_bridge.pddl.task import FactLike, PlanningTask
from plan_bridge.planning.planner import Planner, PlanResult, PlanStatus, UPPlanner
from plan_bridge.planning.worker import WorkerPool

__all__ = ["FAST_DOWNWARD_CONFIGS", "PlannerPortfolio", "fast_downward_portfolio"]

#: Fast Downward search configurations by name (``lama-first`` is the engine's default).
#: Written without spaces: up-fast-downward splits the configuration on whitespace.
FAST_DOWNWARD_CONFIGS: Mapping[str, Mapping[str, str]] = {
    "lama-first": {},
    "add-wastar": {
        "fast_downward_search_config": "let(hadd,add(),lazy_wastar([hadd],w=3,preferred=[hadd]))"
    },
    "cg-eager": {
        "fast_downward_search_config": "let(hcg,cg(),eager_greedy([hcg],preferred=[hcg]))"
    },
    "ff-lazy": {"fast_downward_search_config": "let(hff,ff(),lazy_greedy([hff],preferred=[hff]))"},
}


def fast_downward_portfolio(
    names: Iterable[str], *, pool: WorkerPool | None = None, first: Planner | None = None
) -> PlannerPortfolio:
    """A portfolio of the named :data:`FAST_DOWNWARD_CONFIGS` (after ``first``, if given)."""
    members: list[Planner] = [] if first is None else [first]
    for name in names:
        if name not in FAST_DOWNWARD_CONFIGS:
            raise ValueError(
                f"unknown Fast Downward configuration {name!r}; configurations: "
                f"{', '.join(FAST_DOWNWARD_CONFIGS)}"
            )
        if first is not None and first.name == name:
            continue
        members.append(
            UPPlanner("fast-downward", pool=pool, params=FAST_DOWNWARD_CONFIGS[name], label=name)
        )
    return PlannerPortfolio(members)


class PlannerPortfolio:
    """Planners that race for one task within one deadline (a :class:`Planner`)."""

    def __init__(self, members: Sequence[Planner], *, parallel: int | None = None) -> None:
        if not members:
            raise ValueError("a planner portfolio needs at least one planner")
        if parallel is not None and parallel < 1:
            raise ValueError(f"parallel must be >= 1, got {parallel}")
        self.members = list(members)
        self.parallel = min(len(self.members), parallel or os.cpu_count() or 1)

    @property
    def name(self) -> str:
        return "portfolio[" + ",".join(m.name for m in self.members) + "]"

    def __repr__(self) -> str:
        return f"PlannerPortfolio({self.members!r}, parallel={self.parallel})"

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
        cancel: threading.Event | None = None,
    ) -> PlanResult:
        """The first plan a member finds within ``timeout`` seconds (its ``planner`` is
        that member's name); without one, a result that lists every member's answer."""
        if timeout <= 0:
            raise ValueError(f"timeout must be positive, got {timeout!r}")
        started = time.monotonic()
        deadline = started + timeout
        state = None if initial_state is None else list(initial_state)
        goal_atoms = None if goal is None else list(goal)
        stop = threading.Event()
        lock = threading.Lock()
        queue = list(self.members)
        results: list[PlanResult] = []
        winner: list[PlanResult] = []
        errors: list[BaseException] = []

        running = [self.parallel]
        settled = threading.Event()

        def slot() -> None:
            try:
                run_members()
            finally:
                with lock:
                    running[0] -= 1
                    if running[0] == 0:
                        settled.set()

        def run_members() -> None:
            while not stop.is_set():
                with lock:
                    if not queue:
                        return
                    member = queue.pop(0)
                    # An equal share of what is left, for this member and the ones
                    # this slot may still have to run after it.
                    rounds = 1 + math.ceil(len(queue) / self.parallel)
                left = deadline - time.monotonic()
                if left <= 0.05:
                    return
                try:
                    result = self._solve_one(member, task, left / rounds, state, goal_atoms, stop)
                except BaseException as exc:  # handed to the caller's thread
                    with lock:
                        errors.append(exc)
                    stop.set()
                    settled.set()
                    return
                with lock:
                    if stop.is_set() and not result.solved:
                        return  # cancelled because another member won
                    results.append(result)
                    if result.solved or result.engine_status == "UNSOLVABLE_PROVEN":
                        winner.append(result)
                        stop.set()
                        settled.set()
                        return

        for i in range(self.parallel):
            threading.Thread(target=slot, name=f"plan-bridge-portfolio-{i}", daemon=True).start()
        # Wait for a winner or for every slot to give up; a member that cannot be
        # cancelled (not a UPPlanner) is left to finish in the background.
        while not settled.wait(0.05):
            if cancel is not None and cancel.is_set():
                stop.set()
                break
        stop.set()
        with lock:
            results = list(results)
        if errors:
            raise errors[0]
        elapsed = time.monotonic() - started
        if winner:
            return _with_time(winner[0], elapsed)
        return self._no_plan(results, timeout, elapsed, cancel)

    @staticmethod
    def _solve_one(
        member: Planner,
        task: PlanningTask,
        timeout: float,
        state: list[FactLike] | None,
        goal: list[FactLike] | None,
        stop: threading.Event,
    ) -> PlanResult:
        if isinstance(member, (UPPlanner, PlannerPortfolio)):
            return member.solve(task, timeout=timeout, initial_state=state, goal=goal, cancel=stop)
        return member.solve(task, timeout=timeout, initial_state=state, goal=goal)

    def _no_plan(
        self,
        results: list[PlanResult],
        timeout: float,
        elapsed: float,
        cancel: threading.Event | None,
    ) -> PlanResult:
        if cancel is not None and cancel.is_set():
            return PlanResult(
                PlanStatus.TIMEOUT,
                planner=self.name,
                planning_time_s=elapsed,
                explanation=f"{self.name}: cancelled",
            )
        answered = {r.planner for r in results}
        lines = [f"{r.planner}: {r.status.value}: {r.explanation}" for r in results]
        lines += [
            f"{m.name}: not started within the {timeout:g} s deadline"
            for m in self.members
            if m.name not in answered
        ]
        statuses = {r.status for r in results}
        if PlanStatus.UNSOLVABLE in statuses:
            status = PlanStatus.UNSOLVABLE
        elif statuses <= {PlanStatus.TIMEOUT}:
            status = PlanStatus.TIMEOUT
        else:
            status = results[0].status
        warnings = tuple(dict.fromkeys(w for r in results for w in r.warnings))
        unreachable = next((r.unreachable_goals for r in results if r.unreachable_goals), ())
        return PlanResult(
            status,
            planner=self.name,
            planning_time_s=elapsed,
            explanation=f"no configuration found a plan within {timeout:g} s: " + "; ".join(lines),
            warnings=warnings,
            unreachable_goals=unreachable,
            engine_status=status.value.upper(),
        )


def _with_time(result: PlanResult, elapsed: float) -> PlanResult:
    import dataclasses

    return dataclasses.replace(result, planning_time_s=elapsed)
