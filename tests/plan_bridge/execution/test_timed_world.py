"""The timed world: faults of a step do not depend on which thread began first."""

from __future__ import annotations

import json
from pathlib import Path

from plan_bridge.execution.timed_world import TimedWorld
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep

COURIER = Path(__file__).resolve().parents[3] / "domains" / "timed_courier"
DRIVE = PlanStep("drive", ("courier", "depot", "hall"))
HOLD = PlanStep("hold-door", ("helper", "hall", "lab"))


def world(seed: int) -> TimedWorld:
    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    return TimedWorld(task, seed=seed, fail_rate=0.5)


def test_two_steps_begun_in_either_order_meet_the_same_faults() -> None:
    for seed in range(12):
        first, second = world(seed), world(seed)
        drive_first = first.begin(DRIVE)[1], first.begin(HOLD)[1]
        hold_second, drive_second = second.begin(HOLD)[1], second.begin(DRIVE)[1]
        assert drive_first == (drive_second, hold_second), seed
        assert sorted(map(repr, first.faults)) == sorted(map(repr, second.faults))


def test_a_step_begun_again_draws_its_next_faults_and_a_restored_world_continues() -> None:
    draws = []
    for seed in range(12):
        one = world(seed)
        _, faults = one.begin(HOLD)
        one.abandon(HOLD)
        saved = json.loads(json.dumps(one.snapshot()))
        assert one.begun == {str(HOLD): 1}  # saved with the world
        again = one.begin(HOLD)[1]
        restored = world(seed)
        restored.restore(saved)
        assert restored.begin(HOLD)[1] == again  # the second attempt, as before the save
        draws.append((faults, again))
    assert any(first != second for first, second in draws)  # attempts draw anew


def test_a_world_restored_mid_step_abandons_the_step_and_can_begin_it_again() -> None:
    one = world(0)
    before = one.facts
    started, _ = one.begin(DRIVE)
    assert started and ("at", "courier", "depot") not in one.facts  # driving: at no place
    saved = json.loads(json.dumps(one.snapshot()))
    restored = world(0)
    restored.restore(saved)
    assert restored.facts == one.facts  # restore is exact, the drive still in progress
    restored.abandon_running()  # the process that drove is gone: the drive stopped
    assert restored.facts == before
    assert restored.begin(DRIVE)[0]  # and a resumed run can drive again
