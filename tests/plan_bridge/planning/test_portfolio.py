"""The planner portfolio, and the planner hooks it uses (engine params, cancel)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanResult, PlanStatus, PlanStep, UPPlanner
from plan_bridge.planning.portfolio import (
    FAST_DOWNWARD_CONFIGS,
    PlannerPortfolio,
    fast_downward_portfolio,
)
from plan_bridge.planning.worker import WorkerPool


class ScriptedPlanner:
    """Answers every solve with ``result`` after ``delay`` seconds; records timeouts."""

    def __init__(self, name: str, result: PlanResult, delay: float = 0.0) -> None:
        self._name = name
        self.result = result
        self.delay = delay
        self.timeouts: list[float] = []

    @property
    def name(self) -> str:
        return self._name

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[Any] | None = None,
        goal: Iterable[Any] | None = None,
    ) -> PlanResult:
        self.timeouts.append(timeout)
        time.sleep(min(self.delay, timeout))
        return PlanResult(
            self.result.status,
            list(self.result.actions),
            planner=self._name,
            explanation=self.result.explanation,
            engine_status=self.result.engine_status,
        )


SOLVED = PlanResult(PlanStatus.SOLVED, [PlanStep("pick", ("ball1", "rooma", "left"))])
TIMED_OUT = PlanResult(PlanStatus.TIMEOUT, explanation="found no plan within the time limit")


@pytest.fixture
def pool() -> WorkerPool:  # type: ignore[misc]
    pool = WorkerPool(max_workers=2)
    yield pool
    pool.close()


def blocks(bench: Path) -> PlanningTask:
    folder = bench / "blocks"
    return load_task(folder / "domain.pddl", folder / "probBLOCKS-8-0.pddl")


@pytest.mark.timeout(30)
def test_the_first_plan_wins_without_waiting_for_a_slow_member(bench: Path) -> None:
    slow = ScriptedPlanner("slow", SOLVED, delay=20.0)
    quick = ScriptedPlanner("quick", SOLVED, delay=0.05)
    result = PlannerPortfolio([slow, quick], parallel=2).solve(blocks(bench), timeout=30)
    assert result.solved and result.planner == "quick"
    assert result.planning_time_s < 20.0


@pytest.mark.timeout(30)
def test_a_member_without_a_plan_frees_its_slot_for_the_next(bench: Path) -> None:
    failing = ScriptedPlanner("failing", TIMED_OUT)
    second = ScriptedPlanner("second", SOLVED)
    result = PlannerPortfolio([failing, second], parallel=1).solve(blocks(bench), timeout=10)
    assert result.solved and result.planner == "second"
    # One slot, two members: the first got half of the deadline.
    assert failing.timeouts == [pytest.approx(5.0, abs=0.1)]


@pytest.mark.timeout(30)
def test_without_any_plan_every_members_answer_is_explained(bench: Path) -> None:
    members = [ScriptedPlanner("a", TIMED_OUT), ScriptedPlanner("b", TIMED_OUT)]
    result = PlannerPortfolio(members, parallel=2).solve(blocks(bench), timeout=5)
    assert result.status is PlanStatus.TIMEOUT
    assert "a: timeout" in result.explanation and "b: timeout" in result.explanation


@pytest.mark.timeout(30)
def test_a_proof_of_unsolvability_ends_the_race(bench: Path) -> None:
    proof = PlanResult(
        PlanStatus.UNSOLVABLE, explanation="proved", engine_status="UNSOLVABLE_PROVEN"
    )
    members = [ScriptedPlanner("prover", proof), ScriptedPlanner("late", SOLVED, delay=20.0)]
    result = PlannerPortfolio(members, parallel=2).solve(blocks(bench), timeout=30)
    assert result.status is PlanStatus.UNSOLVABLE and result.planner == "prover"


def test_bad_portfolios_are_refused_with_the_allowed_names() -> None:
    with pytest.raises(ValueError, match="at least one planner"):
        PlannerPortfolio([])
    with pytest.raises(ValueError, match="configurations: lama-first"):
        fast_downward_portfolio(["lama-fist"])


@pytest.mark.timeout(120)
def test_fast_downward_configurations_race_and_the_loser_is_killed(
    bench: Path, pool: WorkerPool
) -> None:
    portfolio = fast_downward_portfolio(["lama-first", "add-wastar"], pool=pool)
    assert [m.name for m in portfolio.members] == ["lama-first", "add-wastar"]
    task = blocks(bench)
    result = portfolio.solve(task, timeout=60)
    assert result.solved and result.planner in ("lama-first", "add-wastar")
    # Both workers are usable afterwards (the loser's was killed and is replaced).
    again = portfolio.solve(task, timeout=60)
    assert again.solved


@pytest.mark.timeout(120)
def test_engine_params_choose_a_search_and_label_the_planner(bench: Path, pool: WorkerPool) -> None:
    planner = UPPlanner(
        "fast-downward", pool=pool, params=FAST_DOWNWARD_CONFIGS["cg-eager"], label="cg-eager"
    )
    result = planner.solve(blocks(bench), timeout=60)
    assert result.solved and result.planner == planner.name == "cg-eager"
    assert planner.engine == "fast-downward"


@pytest.mark.timeout(120)
def test_cancelling_a_solve_kills_its_planner_process(bench: Path, pool: WorkerPool) -> None:
    folder = bench / "visitall-sat11-strips"
    task = load_task(folder / "domain.pddl", folder / "problem14.pddl")
    planner = UPPlanner("pyperplan", pool=pool)  # slow on this problem: still searching
    cancel = threading.Event()
    threading.Timer(1.0, cancel.set).start()
    result = planner.solve(task, timeout=60, cancel=cancel)
    assert result.status is PlanStatus.TIMEOUT
    assert "cancelled" in result.explanation
