"""Every parseable IPC benchmark problem runs to the goal, with and without faults.

This is ``plan-bridge run DOMAIN.pddl --problem P [--fail-rate 0.2 --seed N]`` done in
process (symbolic skills, the Executive with the default policy), to stay fast. The
goal-reached rate over more seeds is measured by benchmarks/bench_fault_rates.py.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from plan_bridge.execution.executive import Executive, ReplanPolicy
from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.missions.mission import load_target
from plan_bridge.planning.planner import UPPlanner, get_planner

FAULT_SEEDS = (0, 1, 2)
FAIL_RATE = 0.2
BENCH_ROOT = (Path(__file__).resolve().parents[3] / ".." / "shared" / "pddl-bench").resolve()
#: Domains unified-planning 1.3 cannot parse (see test_domain).
UNPARSEABLE = {"storage"}
#: Plans of 164 and 272 steps: with failures injected, a run takes tens of seconds.
SLOW_DOMAINS = {"visitall-sat11-strips"}


def _problems(*, smallest_only: bool = False) -> list[Any]:
    params = []
    if not BENCH_ROOT.is_dir():
        return params
    for folder in sorted(p for p in BENCH_ROOT.iterdir() if p.is_dir()):
        if folder.name in UNPARSEABLE:
            continue
        found = sorted(p for p in folder.glob("*.pddl") if p.name != "domain.pddl")
        if smallest_only:
            found = [min(found, key=lambda p: p.stat().st_size)]
        slow = smallest_only and folder.name in SLOW_DOMAINS
        params.extend(
            pytest.param(
                folder / "domain.pddl",
                problem,
                id=f"{folder.name}/{problem.stem}",
                marks=[pytest.mark.slow] if slow else [],
            )
            for problem in found
        )
    return params


@pytest.fixture(scope="module")
def planner() -> UPPlanner:
    planner = get_planner("fast-downward")
    planner.warm_up()
    return planner


def run(
    domain: Path, problem: Path, planner: UPPlanner, *, seed: int = 0, fail_rate: float = 0.0
) -> tuple[Executive, SimulatedWorld]:
    target = load_target(domain, problem)
    setup = target.setup(seed=seed, fail_rate=fail_rate)
    assert setup.skills.check(target.task) == []
    executive = Executive(target.task, setup.skills, planner, policy=ReplanPolicy())
    executive.execute()
    return executive, setup.world


@pytest.mark.timeout(120)
@pytest.mark.parametrize(("domain", "problem"), _problems())
def test_every_parseable_bench_problem_runs_to_the_goal_without_failures(
    domain: Path, problem: Path, planner: UPPlanner
) -> None:
    executive, world = run(domain, problem, planner)
    report = executive.report
    assert world.goal_reached() and world.faults_injected == 0
    assert report.outcome == "succeeded" and report.goal_reached, report.explanation
    assert report.actions_failed == 0 and report.replans == 0 and report.planner_calls == 1
    assert report.actions_executed == len(report.final_plan) > 0


_RATES: dict[str, tuple[int, int, int]] = {}
"""Problem -> (runs, goal reached, failed actions), printed by the summary test."""


@pytest.mark.timeout(200)
@pytest.mark.parametrize(("domain", "problem"), _problems(smallest_only=True))
def test_with_injected_failures_runs_reach_the_goal_through_recovery(
    domain: Path, problem: Path, planner: UPPlanner
) -> None:
    reached = faults = 0
    decisions: set[str] = set()
    for seed in FAULT_SEEDS:
        executive, world = run(domain, problem, planner, seed=seed, fail_rate=FAIL_RATE)
        report = executive.report
        assert report.outcome in ("succeeded", "aborted")
        # The executive, its belief and the simulated world agree on the goal.
        assert report.goal_reached == (report.outcome == "succeeded"), report.explanation
        assert world.goal_reached() == report.goal_reached
        assert report.actions_failed == world.faults_injected
        if not report.goal_reached:
            # Only the budget may stop a run: the planner always found plans.
            assert "budget" in report.explanation, report.explanation
        reached += report.goal_reached
        faults += report.actions_failed
        decisions |= {d["decision"] for d in report.decisions}
    _RATES[f"{domain.parent.name}/{problem.stem}"] = (len(FAULT_SEEDS), reached, faults)
    assert faults == 0 or decisions & {"retry", "continue", "repair", "replan"}
    # At most one of the seeds may exhaust the replanning budget.
    assert reached >= len(FAULT_SEEDS) - 1


def test_goal_reached_rate_with_injected_failures_is_high(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Summary of the runs above (run in file order; skipped when they did not run)."""
    if not _RATES:
        pytest.skip("the fault-injection runs did not run")
    runs = sum(r for r, _, _ in _RATES.values())
    reached = sum(g for _, g, _ in _RATES.values())
    faults = sum(f for _, _, f in _RATES.values())
    with capsys.disabled():
        print(
            f"\n[bench runs] fail rate {FAIL_RATE}, seeds {FAULT_SEEDS}: goal reached in "
            f"{reached}/{runs} runs ({reached / runs:.0%}) over {len(_RATES)} problems, "
            f"{faults} failed actions"
        )
    assert faults > 0
    assert reached / runs >= 0.8
