"""Planner worker processes: priming a parse while the client parses."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import get_planner
from plan_bridge.planning.worker import ProblemText, Worker, WorkerPool


@pytest.mark.timeout(120)
def test_a_primed_task_is_solved_from_the_workers_parse(bench: Path) -> None:
    pool = WorkerPool(max_workers=1)
    try:
        task = load_task(
            bench / "gripper" / "domain.pddl", bench / "gripper" / "prob01.pddl", prime=pool
        )
        result = get_planner("fast-downward", pool=pool).solve(task, timeout=60)
        assert result.solved
        assert result.problem_reused
    finally:
        pool.close()


@pytest.mark.timeout(120)
def test_an_unprimed_task_is_parsed_by_the_solve(bench: Path) -> None:
    pool = WorkerPool(max_workers=1)
    try:
        task = load_task(bench / "gripper" / "domain.pddl", bench / "gripper" / "prob01.pddl")
        result = get_planner("fast-downward", pool=pool).solve(task, timeout=60)
        assert result.solved
        assert not result.problem_reused
    finally:
        pool.close()


@pytest.mark.timeout(120)
def test_a_prime_that_fails_to_parse_is_answered_by_the_solve() -> None:
    worker = Worker()
    try:
        base = ProblemText.of("(define (domain d))", "(define (problem p) (:domain d) (:goal")
        worker.prime(base)
        assert worker.knows(base.key)
        reply = worker.solve("fast-downward", base, timeout=60)
        # The worker forgot nothing it had not parsed: the solve sent the text again
        # and got the parser's error, not a "missing-base" loop or a hang.
        assert reply.outcome == "error"
        assert reply.message
        assert worker.is_alive()
    finally:
        worker.close()


@pytest.mark.timeout(120)
def test_priming_a_large_problem_text_then_solving_it(bench: Path) -> None:
    # More text than a pipe buffer holds, written while the worker still imports UP.
    domain = (bench / "gripper" / "domain.pddl").read_text()
    problem = (bench / "gripper" / "prob01.pddl").read_text() + ";" + "x" * 300_000 + "\n"
    base = ProblemText.of(domain, problem)
    worker = Worker()
    try:
        worker.prime(base)
        reply = worker.solve("fast-downward", base, timeout=60)
        assert reply.outcome == "result", reply.message
        assert reply.status.startswith("SOLVED")
        assert reply.reused
    finally:
        worker.close()


@pytest.mark.timeout(60)
def test_pool_primes_a_text_once_and_not_after_closing(bench: Path) -> None:
    pool = WorkerPool(max_workers=2)
    domain = (bench / "gripper" / "domain.pddl").read_text()
    base = ProblemText.of(domain, (bench / "gripper" / "prob01.pddl").read_text())
    try:
        pool.prime(base)
        pool.prime(base)
        assert pool._count == 1
        with pool.worker(prefer=base.key) as worker:
            assert worker.knows(base.key)
    finally:
        pool.close()
    pool.prime(ProblemText.of(domain, "(define (problem other))"))
    assert pool._count == 0
