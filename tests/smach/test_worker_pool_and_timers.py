"""The shared thread pool of Concurrence and the shared timer thread."""

from __future__ import annotations

import threading

import pytest

from smach import timers, worker_pool


@pytest.mark.timeout(10)
def test_pool_runs_tasks_that_block_each_other_without_deadlock() -> None:
    # Each task waits for the next one to start: needs as many threads as tasks.
    events = [threading.Event() for _ in range(6)]
    done = threading.Barrier(7)

    def task(i: int) -> None:
        events[i].set()
        if i + 1 < len(events):
            events[i + 1].wait(5)
        done.wait(5)

    for i in range(6):
        worker_pool.submit(lambda i=i: task(i))
    done.wait(5)
    assert all(e.is_set() for e in events)


@pytest.mark.timeout(10)
def test_a_task_is_either_cancelled_before_it_starts_or_runs_exactly_once() -> None:
    for _ in range(20):
        ran = threading.Event()
        runs: list[int] = []

        def victim(runs: list[int] = runs, ran: threading.Event = ran) -> None:
            runs.append(1)
            ran.set()

        worker_pool.submit(victim)
        cancelled = worker_pool.cancel(victim)
        if not cancelled:
            assert ran.wait(5)
        else:
            assert not ran.wait(0.05)
        assert len(runs) == (0 if cancelled else 1)
        assert worker_pool.cancel(victim) is False


@pytest.mark.timeout(10)
def test_timers_fire_in_deadline_order_and_cancel_stops_them() -> None:
    fired: list[str] = []
    done = threading.Event()
    timers.schedule(0.06, lambda: (fired.append("late"), done.set()))
    timers.schedule(0.02, lambda: fired.append("early"))
    cancelled = timers.schedule(0.04, lambda: fired.append("cancelled"))
    assert cancelled.cancel()
    assert done.wait(5)
    assert fired == ["early", "late"]
    assert not cancelled.cancel() or cancelled.cancelled


@pytest.mark.timeout(10)
def test_a_raising_timer_callback_does_not_stop_the_timer_thread() -> None:
    done = threading.Event()
    timers.schedule(0.0, lambda: 1 / 0)
    timers.schedule(0.01, done.set)
    assert done.wait(5)
