"""Harness of the mission tests (domains/*): what every mission is run and checked with.

It runs a mission planned (the executive with the domain's skills) or scripted (the
domain's hand-written baseline) for one seed and fault rate, and sweeps over seeds.
Planner answers are memoised across runs (see :class:`MemoPlanner`), and the planners
and the 20-seed sweeps are made once per test session, so that the checks of several
test files share them.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import MissionSetup, Target, load_target
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask, parse_fact
from plan_bridge.planning.planner import Planner, PlanResult, PlanStatus, get_planner
from smach.testing import EventRecorder

REPO = Path(__file__).resolve().parents[2]
DOMAINS = REPO / "domains"
PLAN_BRIDGE = Path(sys.executable).parent / "plan-bridge"

#: The outcomes a mission may end with; anything else (an exception, a hang) is a bug.
DEFINED_OUTCOMES = ("succeeded", "aborted")
SEEDS = range(20)
RATES = (0.1, 0.2)


@dataclass(frozen=True)
class Mission:
    """How a mission is swept over seeds and what its runs must show."""

    name: str
    sweep: str
    """The problem of the 20-seed sweeps."""
    planner: str
    """The planner of the sweeps: pyperplan where Fast Downward would take too long."""
    seed: int
    """A seed whose run at fault rate 0.2 is run again to check it is reproducible."""
    min_faults: int
    """Faults at least over a sweep (the faults are real)."""
    scripted_outcomes: tuple[str, ...] = DEFINED_OUTCOMES
    """The outcomes of the scripted baseline, success first."""

    def __str__(self) -> str:
        return self.name


MISSIONS = (
    Mission("door_opening", "p02", "fast-downward", seed=5, min_faults=20),
    Mission("fetch_drink", "p01", "fast-downward", seed=7, min_faults=10),
    Mission("recharge", "p02", "fast-downward", seed=3, min_faults=10),
    Mission("table_clearing", "p01", "pyperplan", 2, 10, ("done", "failed", "preempted")),
    Mission("two_robot_delivery", "p01", "pyperplan", 1, 10, ("done", "failed", "preempted")),
)
BY_NAME = {m.name: m for m in MISSIONS}


class MemoPlanner:
    """A planner that remembers its answers, keyed by everything a solve depends on.

    Fast Downward is deterministic: the same task from the same initial state gets
    the same plan. Runs of different seeds start from the same state and often
    replan from the same beliefs, so memoising keeps 20-seed sweeps within the test
    budget without changing a single decision of the executive.
    """

    def __init__(self, planner: Planner) -> None:
        self.planner = planner
        self._answers: dict[tuple[Any, ...], PlanResult] = {}
        self._lock = threading.Lock()
        self.solves = 0

    @property
    def name(self) -> str:
        return self.planner.name

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
    ) -> PlanResult:
        facts: frozenset[Fact] = (
            frozenset(parse_fact(f) for f in initial_state)
            if initial_state is not None
            else task.initial_facts
        )
        goals = frozenset(parse_fact(g) for g in goal) if goal is not None else None
        key = (task.name, task.goal_facts, task.goal_is_conjunctive, facts, goals)
        with self._lock:
            known = self._answers.get(key)
        if known is not None:
            return known
        if goals is None:
            result = self.planner.solve(task, timeout=timeout, initial_state=facts)
        else:
            result = self.planner.solve(task, timeout=timeout, initial_state=facts, goal=goals)
        self.solves += 1
        if result.status in (PlanStatus.SOLVED, PlanStatus.UNSOLVABLE):
            with self._lock:
                self._answers[key] = result
        return result


@cache
def target(name: str, problem: str | None = None) -> Target:
    return load_target(DOMAINS / name, problem)


@cache
def planner(engine: str = "fast-downward") -> MemoPlanner:
    """The session's memoising planner of ``engine``."""
    return MemoPlanner(get_planner(engine))


@dataclass(frozen=True)
class Run:
    """One mission run: everything that must be the same for the same seed (and wall time)."""

    mode: str
    seed: int
    outcome: str
    goal_reached: bool
    faults: int
    sim_time: float
    wall_s: float = field(compare=False)
    planner_calls: int = 0
    executed: tuple[str, ...] = ()
    fault_log: tuple[tuple[float, str, str, str], ...] = ()
    """(time, kind, action, detail) per fault; sorted where robots may act concurrently."""
    decisions: tuple[str, ...] = ()
    facts: frozenset[Fact] = frozenset()
    """The true facts of the world at the end."""


def _run(
    mode: str, seed: int, outcome: str, world: Any, started: float, *, concurrent: bool, **more: Any
) -> Run:
    """The :class:`Run` of a run that ended with ``outcome`` in ``world``.

    ``concurrent``: robots acted at the same time, so the fault log, interleaved by
    thread timing, is sorted (each fault has its robot's clock).
    """
    log = [(f.time, f.kind, f.action, f.detail) for f in world.faults]
    return Run(
        mode,
        seed,
        outcome,
        world.goal_reached(),
        world.faults_injected,
        world.sim_time,
        time.monotonic() - started,
        fault_log=tuple(sorted(log) if concurrent else log),
        facts=world.facts,
        **more,
    )


def run_planned(
    mission: Target,
    seed: int,
    fail_rate: float,
    planner: Planner,
    recorder: EventRecorder | None = None,
) -> Run:
    started = time.monotonic()
    setup = mission.setup(seed=seed, fail_rate=fail_rate)
    executive = Executive(
        mission.task, setup.skills, planner, sense=setup.sense, concurrent=setup.concurrent
    )
    if recorder is not None:
        executive.add_listener(recorder)
    outcome = executive.execute() or ""
    # The executive's belief follows the world: it claims success exactly when it is true.
    assert executive.report.goal_reached == setup.world.goal_reached()
    report = executive.report
    return _run(
        "planned",
        seed,
        outcome,
        setup.world,
        started,
        concurrent=setup.concurrent,
        planner_calls=report.planner_calls,
        executed=tuple(sorted(report.executed) if setup.concurrent else report.executed),
        decisions=tuple(d["decision"] for d in report.decisions),
    )


def run_scripted(mission: Target, seed: int, fail_rate: float) -> Run:
    started = time.monotonic()
    assert mission.module is not None
    baseline = mission.module.scripted(mission.task, seed=seed, fail_rate=fail_rate)
    outcome = baseline.machine.execute() or ""
    # A hand-written machine may run robots concurrently too (two_robot_delivery).
    return _run("scripted", seed, outcome, baseline.world, started, concurrent=True)


def setup_with_fault(mission: Target, kind: str, fail_rate: float = 0.1) -> MissionSetup:
    """The setup of the first seed whose world starts with a fault of ``kind``."""
    for seed in SEEDS:
        setup = mission.setup(seed=seed, fail_rate=fail_rate)
        if any(f.kind == kind for f in setup.world.faults):
            return setup
    raise AssertionError(f"no seed of {list(SEEDS)} starts with a fault {kind!r}")


def sweep_planned(
    mission: Target, seeds: Iterable[int], fail_rate: float, planner: Planner
) -> list[Run]:
    """Planned runs of ``seeds``, two at a time (one per planner worker on two cores).

    Runs share nothing but the planner, whose answers do not depend on timing, so
    the results are the same as one by one; they come back in seed order.
    """
    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="mission") as pool:
        return list(pool.map(lambda seed: run_planned(mission, seed, fail_rate, planner), seeds))


@cache
def sweep(name: str, fail_rate: float) -> tuple[Run, ...]:
    """The planned runs of ``name``'s sweep problem over :data:`SEEDS` (once a session)."""
    mission = BY_NAME[name]
    return tuple(
        sweep_planned(target(name, mission.sweep), SEEDS, fail_rate, planner(mission.planner))
    )


def success_rate(runs: Sequence[Run]) -> float:
    return sum(r.goal_reached for r in runs) / len(runs)


def summary(label: str, runs: Sequence[Run]) -> str:
    """``fetch_drink p01 planned fail 0.1: 20/20 goals (100%), ...`` for the test log."""
    reached = sum(r.goal_reached for r in runs)
    mean_sim = sum(r.sim_time for r in runs) / len(runs)
    mean_wall = sum(r.wall_s for r in runs) / len(runs)
    faults = sum(r.faults for r in runs) / len(runs)
    return (
        f"{label}: {reached}/{len(runs)} goals ({reached / len(runs):.0%}), "
        f"{faults:.1f} faults/run, simulated {mean_sim:.0f} s/run, wall {mean_wall:.2f} s/run"
    )


def plan_bridge(
    *commands: Sequence[str], timeout: float = 90.0
) -> list[subprocess.CompletedProcess[str]]:
    """Run ``plan-bridge`` commands of this environment side by side (they are slow
    to start: each imports unified-planning and starts a planner worker)."""
    started = [
        (
            command,
            subprocess.Popen(
                [str(PLAN_BRIDGE), *command],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                cwd=REPO,
            ),
        )
        for command in commands
    ]
    results = []
    for command, process in started:
        try:
            out, err = process.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            out, err = process.communicate()
        results.append(subprocess.CompletedProcess(command, process.returncode, out, err))
    return results


def load_generator(name: str) -> Any:
    """Import ``domains/<name>/generate.py`` as a module."""
    import importlib.util

    path = DOMAINS / name / "generate.py"
    spec = importlib.util.spec_from_file_location(f"{name}_generate", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
