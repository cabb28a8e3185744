"""Which steps of a plan serve which order, and which robots do them."""

from __future__ import annotations

from pathlib import Path

from plan_bridge.execution.semantics import ActionModel
from plan_bridge.orders.assignment import agents_of, order_work
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.types import PlanStep

COURIERS = Path(__file__).parents[1] / "data" / "couriers"


def step(text: str) -> PlanStep:
    action, *arguments = text.split()
    return PlanStep(action, tuple(arguments))


def test_the_agents_are_the_objects_most_actions_take_first() -> None:
    task = load_task(COURIERS / "domain.pddl", COURIERS / "problems" / "line.pddl")
    assert agents_of(task) == {"ann", "bo"}
    assert agents_of(task, {"ann": "courier", "cy": "courier", "p1": "parcel"}) == {"ann", "cy"}


def test_a_robots_steps_up_to_its_achiever_serve_that_order_and_no_other() -> None:
    task = load_task(COURIERS / "domain.pddl", COURIERS / "problems" / "line.pddl")
    plan = [
        step("walk ann west mid"),  # 0: ann's first order
        step("take ann p1 mid"),  # 1
        step("walk bo annex east"),  # 2: bo's only order
        step("walk ann mid east"),  # 3
        step("leave ann p1 east"),  # 4: p1 delivered
        step("take bo p2 east"),  # 5
        step("take ann p2 east"),  # 6: after ann's last order: serves none
        step("walk bo east mid"),  # 7
        step("leave bo p2 mid"),  # 8: p2 delivered
        step("walk ann east annex"),  # 9: after ann's last order: serves none
    ]
    work = order_work(
        plan,
        {"p1": [("lies", "p1", "east")], "p2": [("lies", "p2", "mid")], "held": [("free", "ann")]},
        ActionModel(task),
        task.initial_facts,
        agents_of(task),
    )
    assert work["p1"].robots == ("ann",) and work["p1"].steps == {0, 1, 3, 4}
    assert work["p2"].robots == ("bo",) and work["p2"].steps == {2, 5, 7, 8}
    # (free ann) holds at the start; the leave adds it again: ann's run up to it.
    assert work["held"].steps == {0, 1, 3, 4}
    assert not any(9 in w.steps for w in work.values())
