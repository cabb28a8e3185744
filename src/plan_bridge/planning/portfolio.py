"""A portfolio of planners: several configurations race within one deadline.

(The replanner of :mod:`plan_bridge.execution` races Fast Downward configurations
through it: :class:`~plan_bridge.execution.policy.ReplanPolicy` ``replan_portfolio``.)

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

import dataclasses
import math
import os
import threading
import time
from collections.abc import Iterable, Mapping, Sequence

from plan_bridge.pddl.task import FactLike, PlanningTask
from plan_bridge.planning.planner import UPPlanner
from plan_bridge.planning.types import Planner, PlanResult, PlanStatus
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
        race = _Race(
            self,
            task,
            started + timeout,
            None if initial_state is None else list(initial_state),
            None if goal is None else list(goal),
        )
        for i in range(self.parallel):
            threading.Thread(
                target=race.slot, name=f"plan-bridge-portfolio-{i}", daemon=True
            ).start()
        results, winner = race.wait(cancel)
        elapsed = time.monotonic() - started
        if winner is not None:
            return dataclasses.replace(winner, planning_time_s=elapsed)
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


class _Race:
    """The members of one :meth:`PlannerPortfolio.solve`, run by ``parallel`` slots."""

    def __init__(
        self,
        portfolio: PlannerPortfolio,
        task: PlanningTask,
        deadline: float,
        state: list[FactLike] | None,
        goal: list[FactLike] | None,
    ) -> None:
        self.portfolio = portfolio
        self.task = task
        self.deadline = deadline
        self.state = state
        self.goal = goal
        self.stop = threading.Event()
        self.settled = threading.Event()
        self.lock = threading.Lock()
        self.queue = list(portfolio.members)
        self.results: list[PlanResult] = []
        self.winner: PlanResult | None = None
        self.errors: list[BaseException] = []
        self.running = portfolio.parallel

    def slot(self) -> None:
        try:
            self._run_members()
        finally:
            with self.lock:
                self.running -= 1
                if self.running == 0:
                    self.settled.set()

    def _next(self) -> tuple[Planner, float] | None:
        """The next member and its share of the time left (None: nothing left)."""
        with self.lock:
            if not self.queue:
                return None
            member = self.queue.pop(0)
            # An equal share of what is left, for this member and the ones this slot
            # may still have to run after it.
            rounds = 1 + math.ceil(len(self.queue) / self.portfolio.parallel)
        left = self.deadline - time.monotonic()
        return None if left <= 0.05 else (member, left / rounds)

    def _run_members(self) -> None:
        while not self.stop.is_set():
            upcoming = self._next()
            if upcoming is None:
                return
            member, budget = upcoming
            try:
                result = self.portfolio._solve_one(
                    member, self.task, budget, self.state, self.goal, self.stop
                )
            except BaseException as exc:  # handed to the caller's thread
                with self.lock:
                    self.errors.append(exc)
                self._end()
                return
            with self.lock:
                if self.stop.is_set() and not result.solved:
                    return  # cancelled because another member won
                self.results.append(result)
                if result.solved or result.engine_status == "UNSOLVABLE_PROVEN":
                    self.winner = result
            if self.winner is not None:
                self._end()
                return

    def _end(self) -> None:
        self.stop.set()
        self.settled.set()

    def wait(self, cancel: threading.Event | None) -> tuple[list[PlanResult], PlanResult | None]:
        """Wait for a winner or for every slot to give up; a member that cannot be
        cancelled (not a UPPlanner) is left to finish in the background."""
        while not self.settled.wait(0.05):
            if cancel is not None and cancel.is_set():
                break
        self.stop.set()
        with self.lock:
            if self.errors:
                raise self.errors[0]
            return list(self.results), self.winner
