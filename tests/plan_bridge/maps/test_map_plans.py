"""Plans of map tasks tidied: a robot's drives to and fro become the drive they amount
to, and the timeline closes up."""

from __future__ import annotations

from typing import Any

import pytest

from plan_bridge.belief import FactSnapshot
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.temporal_network import retimed
from plan_bridge.maps.plans import tidied
from plan_bridge.maps.tasks import RouteTasks
from plan_bridge.planning.types import PlanStep


def timed(*steps: tuple[str, tuple[str, ...], float]) -> list[PlanStep]:
    """Steps one after the other, each with its duration."""
    out, at = [], 0.0
    for action, args, duration in steps:
        out.append(PlanStep(action, args, at, duration))
        at += duration + 0.001
    return out


@pytest.fixture
def fetch(house: Any) -> tuple[Any, FactSnapshot, ActionModel, dict[tuple[str, ...], float]]:
    view = RouteTasks(house())
    task = view.task_for(view.belief(), [("at", "apple", "shelf_top")])
    model = ActionModel(task)
    state = FactSnapshot(task.initial_facts, model.initial_values())
    return task, state, model, dict(task.spec.values)


def test_drives_to_and_fro_become_one_drive_and_the_plan_closes_up(fetch: Any) -> None:
    task, state, model, values = fetch
    metres = values[("metres", "kitchen", "desk_top")]
    far = values[("metres", "desk_top", "shelf_top")]
    plan = timed(
        ("navigate", ("robot", "kitchen", "desk_top"), metres),
        ("navigate", ("robot", "desk_top", "kitchen"), metres),
        ("navigate", ("robot", "kitchen", "desk_top"), metres),
        ("pick", ("robot", "apple", "desk_top", "desk"), 2.0),
        ("navigate", ("robot", "desk_top", "kitchen"), metres),
        ("navigate", ("robot", "kitchen", "shelf_top"), values[("metres", "kitchen", "shelf_top")]),
        ("place", ("robot", "apple", "shelf_top", "shelf"), 2.0),
    )
    assert model.check_plan(plan, state).valid
    tidy = tidied(plan, task, state, model)
    assert [str(s) for s in tidy] == [
        "(navigate robot kitchen desk_top)",
        "(pick robot apple desk_top desk)",
        "(navigate robot desk_top shelf_top)",
        "(place robot apple shelf_top shelf)",
    ]
    assert tidy[2].duration == pytest.approx(far)
    assert tidy[1].start == pytest.approx(metres, abs=0.002)
    assert tidy[-1].start == pytest.approx(metres + 2.0 + far, abs=0.005)
    assert model.check_plan(tidy, state).valid


def test_a_plan_without_detours_is_left_as_it_is(fetch: Any) -> None:
    task, state, model, values = fetch
    plan = timed(
        ("navigate", ("robot", "kitchen", "desk_top"), values[("metres", "kitchen", "desk_top")]),
        ("pick", ("robot", "apple", "desk_top", "desk"), 2.0),
    )
    assert tidied(plan, task, state, model) == plan


def test_retiming_keeps_the_order_and_the_overlaps_of_a_plan(fetch: Any) -> None:
    _, _, model, _ = fetch
    steps = [
        PlanStep("navigate", ("robot", "kitchen", "desk_top"), 0.0, 1.0),
        PlanStep("pick", ("robot", "apple", "desk_top", "desk"), 5.0, 2.0),  # a 4 s gap
    ]
    again = retimed(steps, model, [1.0, 2.0])
    assert again[0].start == 0.0 and again[1].start == pytest.approx(1.001)
