"""Random nested machines, preempted at random moments: every run ends, nothing leaks."""

from __future__ import annotations

import threading
import time

import pytest

from smach import worker_pool
from smach.stress import stress


def _non_pool_threads() -> set[str]:
    return {
        t.name
        for t in threading.enumerate()
        if not t.name.startswith(("smach-worker-", "smach-timers"))
    }


@pytest.mark.timeout(300)
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_machines_always_end_with_a_declared_outcome_or_a_smach_error(seed: int) -> None:
    before = _non_pool_threads()
    report = stress(150, seed, time_bound=10.0)
    assert report.hung == 0
    assert report.unexpected == []
    assert report.runs == 150
    assert report.preempts_sent > 50
    assert sum(report.outcomes.values()) + report.errors == 150
    assert report.outcomes.get("preempted", 0) > 0
    # No thread outlives its run (pool workers are reused, not leaked).
    deadline = time.monotonic() + 5
    while _non_pool_threads() - before and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _non_pool_threads() - before == set()
    assert worker_pool.size() < 200
