"""Clocks: the wall clock, and a simulated clock whose participants take turns in
simulated time, so that what threads do on it comes in one order whatever the threads."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import pytest
from thread_load import busy_thread

from plan_bridge.execution import clock as clock_module
from plan_bridge.execution.clock import WALL_CLOCK, PacedClock, SimClock, WallClock, clock_of
from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import load_task

pytestmark = pytest.mark.timeout(60)

COURIER = Path(__file__).resolve().parents[3] / "domains" / "timed_courier"


def run_participants(
    clock: SimClock, bodies: dict[int, Callable[[], object]], start_order: list[int]
) -> None:
    """Admit one thread per key (in key order, as a dispatcher does), start them in
    ``start_order`` and wait for all of them."""
    tickets = {key: clock.admit(key) for key in sorted(bodies)}

    def body(key: int) -> None:
        with clock.turn(tickets[key]):
            bodies[key]()

    threads = {key: threading.Thread(target=body, args=(key,), daemon=True) for key in bodies}
    for key in start_order:
        threads[key].start()
    for thread in threads.values():
        thread.join(timeout=30)
        assert not thread.is_alive()


def test_the_wall_clock_reads_monotonic_time_and_a_preempted_wait_returns_false() -> None:
    clock = WallClock()
    assert not clock.simulated
    before = clock.now()
    assert clock.sleep_until(before)  # a time already passed: at once
    assert clock.now() >= before
    assert not clock.sleep_until(before + 3600, lambda: True)  # preempted: at once
    ticket = clock.admit(0)
    with clock.turn(ticket):  # orders nothing
        pass


def test_a_paced_clock_reads_wall_time_divided_by_its_scale_and_waits_the_paced_time() -> None:
    clock = PacedClock(0.01)  # 100 simulated seconds per wall second
    assert clock.simulated and clock.now() < 5.0
    began = time.monotonic()
    assert clock.sleep_until(clock.now() + 20.0)  # 20 simulated seconds: 0.2 s of wall time
    assert time.monotonic() - began >= 0.19
    assert not clock.sleep_until(clock.now() + 3600, lambda: True)  # preempted: at once
    condition = clock.condition()
    began = time.monotonic()
    with condition:
        condition.wait_until(clock.now() + 10.0)  # not notified: until 0.1 s of wall time
    assert time.monotonic() - began >= 0.09
    with pytest.raises(ValueError, match="above 0"):
        PacedClock(0)


def test_a_simulated_world_owns_a_simulated_clock_and_no_world_means_the_wall_clock() -> None:
    world = SimulatedWorld(load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl"))
    assert clock_of(world) is world.clock and world.clock.simulated
    assert clock_of(None) is WALL_CLOCK
    world.time_scale = 0.5
    assert world.clock.time_scale == 0.5
    with pytest.raises(ValueError, match="time_scale must be 0 or more"):
        world.time_scale = -1.0


def test_a_thread_alone_moves_the_simulated_clock_without_waiting(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    slept: list[float] = []
    wall = SimpleNamespace(monotonic=time.monotonic, sleep=slept.append)
    monkeypatch.setattr(clock_module, "time", wall)
    clock = SimClock()
    assert clock.sleep_until(12.5)
    assert clock.now() == 12.5
    assert clock.sleep(2.5) and clock.now() == 15.0
    assert not clock.sleep(100.0, lambda: True)  # preempted: the time did not pass
    assert clock.now() == 15.0
    assert slept == []  # no time scale: nothing waited on the wall


def test_with_a_time_scale_the_clock_is_paced_in_wall_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    wall = SimpleNamespace(t=0.0)

    def fake_sleep(seconds: float) -> None:
        wall.t += seconds

    monkeypatch.setattr(
        clock_module, "time", SimpleNamespace(monotonic=lambda: wall.t, sleep=fake_sleep)
    )
    clock = SimClock(time_scale=0.5)
    assert clock.sleep_until(4.0)  # alone
    assert wall.t == pytest.approx(2.0)
    run_participants(  # participants: the clock moves 4 -> 6 -> 9, paced each time
        clock, {0: lambda: clock.sleep_until(6.0), 1: lambda: clock.sleep_until(9.0)}, [1, 0]
    )
    assert clock.now() == 9.0
    assert wall.t == pytest.approx(4.5)
    clock.time_scale = 1e6
    assert clock.sleep(1.0)
    assert wall.t == pytest.approx(4.5 + clock_module.MAX_PACE_S)  # a long wait is capped


@pytest.mark.parametrize("start_order", [[0, 1, 2], [2, 1, 0], [1, 2, 0]])
def test_participants_act_in_simulated_time_order_ties_broken_by_key(
    start_order: list[int],
) -> None:
    clock = SimClock()
    seen: list[tuple[float, str]] = []

    def actor(name: str, wakes: list[float]) -> Callable[[], None]:
        def act() -> None:
            seen.append((clock.now(), f"{name} starts"))
            for when in wakes:
                assert clock.sleep_until(when)
                seen.append((clock.now(), name))

        return act

    with busy_thread():
        run_participants(
            clock,
            {2: actor("c", [1.0, 5.0]), 0: actor("a", [5.0, 7.0]), 1: actor("b", [5.0, 6.0])},
            start_order,
        )
    assert seen == [
        (0.0, "a starts"),
        (0.0, "b starts"),
        (0.0, "c starts"),
        (1.0, "c"),
        (5.0, "a"),
        (5.0, "b"),
        (5.0, "c"),
        (6.0, "b"),
        (7.0, "a"),
    ]


def test_a_notified_participant_runs_before_the_clock_moves_on() -> None:
    clock = SimClock()
    condition = clock.condition()
    state = {"ended": False}
    woke_at: list[float] = []

    def waiter() -> None:
        with condition:
            while not state["ended"]:
                condition.wait_until(None)
            woke_at.append(clock.now())

    def ender() -> None:
        clock.sleep_until(3.0)
        with condition:
            state["ended"] = True
            condition.notify_all()
        # Ending now hands the turn over: the waiter, not the sleeper due at 3.5.

    def later() -> None:
        clock.sleep_until(3.5)
        woke_at.append(clock.now())

    with busy_thread():
        run_participants(clock, {-1: waiter, 0: ender, 1: later}, [1, 0, -1])
    assert woke_at == [3.0, 3.5]


def test_a_preempted_sleeper_wakes_at_once_and_a_deadline_ends_a_condition_wait() -> None:
    clock = SimClock()
    condition = clock.condition()
    preempted = threading.Event()
    seen: list[tuple[str, float, bool]] = []

    def sleeper() -> None:
        ok = clock.sleep_until(100.0, preempted.is_set)
        seen.append(("sleeper", clock.now(), ok))

    def preempter() -> None:
        clock.sleep_until(2.0)
        preempted.set()  # (as a step's over-all watcher preempts another's skill)
        seen.append(("preempter", clock.now(), True))

    def timed_waiter() -> None:
        with condition:
            condition.wait_until(1.0)  # nobody notifies: the deadline ends the wait
        seen.append(("waiter", clock.now(), True))

    run_participants(clock, {0: sleeper, 1: preempter, 2: timed_waiter}, [0, 1, 2])
    assert seen == [("waiter", 1.0, True), ("preempter", 2.0, True), ("sleeper", 2.0, False)]
    assert clock.now() == 2.0  # the clock never went to the preempted sleeper's 100 s


def test_a_participant_waiting_inside_nested_holds_of_a_condition_lets_others_take_it() -> None:
    clock = SimClock()
    condition = clock.condition()
    state = {"done": False}
    seen: list[float] = []

    def waiter() -> None:
        with condition, condition:  # held twice (a notifier may hold it already)
            while not state["done"]:
                condition.wait_until(None)
        seen.append(clock.now())

    def notifier() -> None:
        clock.sleep_until(1.0)
        with condition:  # would wait for ever if the waiter still held a level
            state["done"] = True
            condition.notify_all()

    run_participants(clock, {0: waiter, 1: notifier}, [0, 1])
    assert seen == [1.0]
