"""Action semantics evaluated against sets of facts."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.execution.semantics import ActionModel
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep

DATA = Path(__file__).parents[1] / "data"


@pytest.fixture(scope="module")
def model() -> ActionModel:
    return ActionModel(
        load_task(DATA / "rooms" / "domain.pddl", DATA / "rooms" / "problems" / "p01.pddl")
    )


def test_ground_action_is_applicable_only_when_its_preconditions_hold(model: ActionModel) -> None:
    facts = model.task.initial_facts
    assert model.ground(PlanStep("move", ("robot1", "hall", "kitchen"))).applicable(facts)
    assert not model.ground(PlanStep("move", ("robot1", "kitchen", "office"))).applicable(facts)


def test_unmet_preconditions_name_the_bound_atoms(model: ActionModel) -> None:
    unmet = model.ground(PlanStep("pick", ("robot1", "cup", "hall"))).unmet_preconditions(
        model.task.initial_facts
    )
    assert unmet == ["(item-at cup hall)"]


def test_effects_delete_then_add_and_universal_conditional_effects_apply(
    model: ActionModel,
) -> None:
    state = model.task.initial_facts | {("holding", "robot1", "cup")}
    state = (state - {("item-at", "cup", "kitchen")}) | {("item-at", "cup", "hall")}
    after = model.ground(PlanStep("move", ("robot1", "hall", "office"))).apply(state)
    assert ("at", "robot1", "office") in after
    assert ("at", "robot1", "hall") not in after
    assert ("item-at", "cup", "hall") not in after  # forall/when effect


def test_existential_precondition_is_checked_over_objects_of_the_type(model: ActionModel) -> None:
    switch = model.ground(PlanStep("switch-on", ("robot1", "hall")))
    facts = model.task.initial_facts
    assert not switch.applicable(facts)
    assert switch.applicable(facts | {("item-at", "cup", "hall")})


def test_check_plan_reports_the_first_inapplicable_step(model: ActionModel) -> None:
    plan = [
        PlanStep("move", ("robot1", "hall", "kitchen")),
        PlanStep("pick", ("robot1", "cup", "hall")),
    ]
    check = model.check_plan(plan, model.task.initial_facts)
    assert not check.valid
    assert check.failed_index == 1
    assert "(item-at cup hall)" in check.reason


def test_check_plan_accepts_a_plan_that_reaches_the_goal(model: ActionModel) -> None:
    plan = [
        PlanStep("move", ("robot1", "hall", "kitchen")),
        PlanStep("pick", ("robot1", "cup", "kitchen")),
        PlanStep("move", ("robot1", "kitchen", "hall")),
        PlanStep("move", ("robot1", "hall", "office")),
        PlanStep("drop", ("robot1", "cup", "office")),
    ]
    check = model.check_plan(plan, model.task.initial_facts)
    assert check.valid and check.goal_reached
    assert model.check_plan(plan[:-1], model.task.initial_facts).reason == (
        "the plan ends without reaching the goal"
    )


def test_regression_gives_what_must_hold_before_the_rest_of_a_plan(model: ActionModel) -> None:
    rest = [PlanStep("drop", ("robot1", "cup", "office"))]
    assert model.regress(rest) == {("at", "robot1", "office"), ("holding", "robot1", "cup")}


def test_wrong_arity_and_unknown_actions_are_reported(model: ActionModel) -> None:
    with pytest.raises(Exception, match="takes 3 arguments"):
        model.ground(PlanStep("move", ("robot1",)))
    with pytest.raises(Exception, match="unknown action 'fly'"):
        model.ground(PlanStep("fly", ()))
