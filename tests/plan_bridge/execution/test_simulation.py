"""The simulated world's helpers for domain worlds: fault draws, facts, variants."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import PlanningTask, load_task

ROOMS = Path(__file__).parents[1] / "data" / "rooms"


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


class FaultyWorld(SimulatedWorld):
    fault_scale = {"slip": 2.0, "never": 0.0, "sure": 50.0}
    variants = ("", "dark")


def test_chance_happens_with_probability_fail_rate_times_the_scale_of_the_kind() -> None:
    world = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    draws = [world.chance("slip") for _ in range(4000)]
    assert 0.37 < sum(draws) / len(draws) < 0.43  # 0.2 x 2.0
    assert all(world.chance("sure") for _ in range(100))  # capped at 1


def test_chance_is_seeded_and_draws_nothing_where_a_fault_cannot_happen() -> None:
    first = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    second = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    assert [first.chance("slip") for _ in range(50)] == [second.chance("slip") for _ in range(50)]
    state = first.rng.getstate()
    assert not first.chance("never")
    assert not FaultyWorld(rooms(), seed=3, fail_rate=0.0).chance("slip")
    assert first.rng.getstate() == state
    with pytest.raises(KeyError):
        first.chance("unknown")


def test_chance_draws_from_the_generator_it_is_given() -> None:
    world = FaultyWorld(rooms(), seed=3, fail_rate=0.2)
    own, state = random.Random(7), world.rng.getstate()
    expected = random.Random(7).random() < 0.4
    assert world.chance("slip", own) == expected
    assert world.rng.getstate() == state
    assert own.getstate() != random.Random(7).getstate()


def test_holds_tells_whether_a_fact_is_true_in_the_world() -> None:
    world = SimulatedWorld(rooms())
    assert world.holds("at", "robot1", "hall")
    assert not world.holds("at", "robot1", "office")


def test_a_world_knows_its_variants_and_refuses_others() -> None:
    assert FaultyWorld(rooms(), variant="dark").variant == "dark"
    assert SimulatedWorld(rooms()).variant == ""
    with pytest.raises(ValueError, match="unknown variant 'dim'; variants: , dark"):
        FaultyWorld(rooms(), variant="dim")
    with pytest.raises(ValueError, match="unknown variant 'dark'"):
        SimulatedWorld(rooms(), variant="dark")
