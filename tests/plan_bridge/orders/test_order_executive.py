"""A mission of orders on a symbolic world: every order accounted for, as they come."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pytest

import smach
from plan_bridge.execution.control import parse_goal
from plan_bridge.execution.simulation import SimulatedWorld, SymbolicSkill, symbolic_skills
from plan_bridge.orders.book import OrderBook
from plan_bridge.orders.order import Order, OrderChanged
from plan_bridge.orders.order_executive import BENCH_S, OrderExecutive
from plan_bridge.pddl.task import Fact, PlanningTask, load_task
from smach.introspection.events import Event

COURIERS = Path(__file__).parents[1] / "data" / "couriers"

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def task() -> PlanningTask:
    return load_task(COURIERS / "domain.pddl", COURIERS / "problems" / "line.pddl")


class Broken(smach.State):
    """A courier that cannot take anything: its hand is broken."""

    def __init__(self) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])

    def execute(self, ud: smach.UserData) -> str:
        return "aborted"


def mission(
    task: PlanningTask,
    *orders: Order,
    broken: str = "",
    closed: bool = True,
    **options: Any,
) -> tuple[OrderExecutive, list[Event]]:
    world = SimulatedWorld(task, seed=1, fail_rate=0.0)
    skills = symbolic_skills(world)
    skills.fallback = lambda step: (
        Broken()
        if step.action == "take" and broken in step.arguments[:1]
        else SymbolicSkill(world, step)
    )

    def goal_of(text: str) -> Sequence[Fact]:
        return [task.check_fact(f) for f in parse_goal(text)]

    executive = OrderExecutive(
        task,
        skills,
        "auto",
        world=world,
        orders=OrderBook(orders, closed=closed),
        goal_of=goal_of,
        **options,
    )
    events: list[Event] = []
    executive.add_listener(events.append)
    return executive, events


def life(events: Sequence[Event]) -> dict[str, list[str]]:
    lives: dict[str, list[str]] = {}
    for event in events:
        if isinstance(event, OrderChanged):
            lives.setdefault(event.order, []).append(event.status)
    return lives


def test_every_order_is_done_as_it_arrives_and_the_summary_counts_them(
    task: PlanningTask,
) -> None:
    executive, events = mission(
        task,
        Order("p1-east", "(lies p1 east)", 0.0),
        Order("p2-west", "(lies p2 west)", 0.0),
        Order("p3-annex", "(lies p3 annex)", 40.0, priority=1),
    )
    assert executive.execute() == "succeeded"
    assert executive.report.goal_reached
    lives = life(events)
    assert set(lives) == {"p1-east", "p2-west", "p3-annex"}
    for statuses in lives.values():
        assert statuses[0] == "queued" and statuses[-1] == "done" and "active" in statuses
    figures = executive.report.orders
    assert (figures["done"], figures["orders"]) == (3, 3)
    assert figures["latency_p50_s"] > 0 and set(figures["busy_share"]) == {"ann", "bo"}
    assert all(s.arrived is not None and s.ended is not None for s in executive.orders.states())
    assert executive.orders.get("p3-annex").arrived == 40.0


def test_an_order_naming_nothing_or_that_no_courier_can_reach_is_refused_and_the_rest_go_on(
    task: PlanningTask,
) -> None:
    executive, _ = mission(
        task,
        Order("typo", "(lies p9 east)", 0.0),
        Order("locked-away", "(lies p4 west)", 0.0),
        Order("fine", "(lies p1 west)", 0.0),
    )
    assert executive.execute() == "succeeded"
    book = executive.orders
    assert book.get("typo").status == "refused"
    assert "unknown object 'p9'" in book.get("typo").reason
    assert book.get("locked-away").status == "refused"
    assert book.get("locked-away").reason.startswith("no robot can reach it: no plan for it")
    assert book.get("fine").status == "done"
    assert "2 refused" in executive.report.explanation


def test_with_no_open_order_the_clock_moves_to_the_next_arrival(task: PlanningTask) -> None:
    executive, _ = mission(task, Order("later", "(lies p2 mid)", 5000.0))
    assert executive.execute() == "succeeded"
    state = executive.orders.get("later")
    assert state.arrived == 5000.0 and state.ended is not None and state.ended > 5000.0
    assert executive.elapsed_s >= 5000.0
    waits = [e for e in executive.report.decisions if e["decision"] == "wait"]
    assert waits and "next arrives at 5000 s" in waits[0]["reason"]


def test_an_order_arriving_while_a_plan_runs_is_planned_for_without_stopping_a_step(
    task: PlanningTask,
) -> None:
    executive, events = mission(
        task, Order("first", "(lies p3 annex)", 0.0), Order("second", "(lies p2 west)", 12.0)
    )
    assert executive.execute() == "succeeded"
    assert {s.status for s in executive.orders.states()} == {"done"}
    preempted = [e for e in events if getattr(e, "outcome", None) == "preempted"]
    assert preempted == []  # the plan held: no step was stopped half-way
    plans = [e for e in events if e.kind == "plan_computed"]
    assert len(plans) >= 2 and "second" in plans[-1].reason


def test_a_live_order_is_taken_and_a_cancelled_one_leaves_the_plan(task: PlanningTask) -> None:
    executive, _ = mission(task, Order("long", "(lies p3 annex)", 0.0), closed=False)
    sent = threading.Event()

    def on_event(event: Event) -> None:
        started = isinstance(event, OrderChanged) and (event.order, event.status) == (
            "long",
            "active",
        )
        if started and not sent.is_set():
            sent.set()
            executive.desk().order({"goal": "(lies p1 west)", "id": "live"})
        if isinstance(event, OrderChanged) and event.order == "live" and event.status == "assigned":
            executive.orders.cancel("long", executive.now(), source="cli")
            executive.orders.close()

    executive.add_listener(on_event)
    assert executive.execute() == "succeeded"
    book = executive.orders
    assert book.get("live").status == "done"
    assert book.get("long").status == "cancelled"
    assert book.get("long").reason == "cancelled (cli)"


def test_a_courier_that_keeps_failing_is_benched_and_the_other_takes_its_order(
    task: PlanningTask,
) -> None:
    executive, _ = mission(task, Order("near-ann", "(lies p3 mid)", 0.0), broken="ann")
    assert executive.execute() == "succeeded"
    state = executive.orders.get("near-ann")
    assert state.status == "done" and state.robots == ("bo",)
    assert state.attempts == 1
    benches = [d for d in executive.report.decisions if d["decision"] == "bench"]
    assert benches and benches[0]["reason"].startswith("ann left out of plans until")
    assert executive.benched["ann"] <= BENCH_S + executive.elapsed_s


def test_an_order_only_a_broken_courier_could_do_fails_with_the_reason(
    task: PlanningTask,
) -> None:
    # bo is broken too: nobody can take p3; the order fails, the other one is done.
    executive, _ = mission(
        task,
        Order("stuck", "(lies p3 mid)", 0.0),
        Order("walk", "(in bo east)", 0.0),
        broken="",
    )
    world_skills = executive.skills
    world_skills.fallback = lambda step: (
        Broken() if step.action == "take" else SymbolicSkill(world_skills.world, step)  # type: ignore[arg-type]
    )
    assert executive.execute() == "succeeded"
    assert not executive.report.goal_reached  # an order failed
    stuck = executive.orders.get("stuck")
    assert stuck.status == "failed" and stuck.attempts == 2
    assert "take" in stuck.reason
    assert executive.orders.get("walk").status == "done"


def test_step_numbers_go_on_across_the_plans_of_the_orders(task: PlanningTask) -> None:
    executive, events = mission(
        task, Order("a", "(lies p1 east)", 0.0), Order("b", "(lies p2 mid)", 30.0)
    )
    assert executive.execute() == "succeeded"
    indices = [e.index for e in events if e.kind == "step_finished"]
    assert len(indices) == len(set(indices)) == executive.report.actions_executed
    assert len([e for e in events if e.kind == "plan_computed"]) >= 2


def test_a_courier_whose_node_is_gone_is_left_out_and_the_other_takes_its_order(
    task: PlanningTask,
) -> None:
    """``robots_gone`` (a robot node's process died, ``run --ros``): planned without."""
    executive, _ = mission(task, Order("near-ann", "(lies p3 mid)", 0.0))
    executive.robots_gone = lambda: {"ann"}
    assert executive.execute() == "succeeded"
    state = executive.orders.get("near-ann")
    assert state.status == "done" and state.robots == ("bo",)
    gone = [d for d in executive.report.decisions if d["decision"] == "gone"]
    assert len(gone) == 1 and gone[0]["reason"].startswith("ann gone (its robot node")


def test_an_order_whose_parcel_a_gone_courier_carries_fails_naming_it(
    task: PlanningTask,
) -> None:
    executive, _ = mission(task, Order("p3-east", "(lies p3 east)", 0.0))
    gone: set[str] = set()

    class DiesWithItsNode(SymbolicSkill):
        """A step of a courier whose node is gone aborts (as RobotLost does over ROS)."""

        def execute(self, ud: smach.UserData) -> str:
            return "aborted" if self.step.arguments[0] in gone else super().execute(ud)

    world = executive.skills.world
    executive.skills.fallback = lambda step: DiesWithItsNode(world, step)  # type: ignore[arg-type]
    executive.robots_gone = lambda: gone

    def on_event(event: Event) -> None:
        # ann's node dies once it has taken the parcel: the parcel goes with it.
        if getattr(event, "kind", "") == "step_finished" and "(take ann p3" in str(
            getattr(event, "action", "")
        ):
            gone.add("ann")

    executive.add_listener(on_event)
    assert executive.execute() == "succeeded"
    state = executive.orders.get("p3-east")
    assert state.status == "failed"
    assert "(carries ann p3): ann gone" in state.reason, state.reason


def test_with_a_courier_gone_the_horizon_is_the_orders_of_the_couriers_left(
    task: PlanningTask,
) -> None:
    executive, events = mission(
        task, Order("a", "(lies p3 mid)", 0.0), Order("b", "(lies p2 west)", 0.0), per_robot=1
    )
    executive.robots_gone = lambda: {"ann"}
    assert executive.execute() == "succeeded"
    assert [executive.orders.get(o).robots for o in ("a", "b")] == [("bo",), ("bo",)]
    plans = [e.reason for e in events if e.kind == "plan_computed"]
    # One courier left, one order a courier: planned one after the other.
    assert plans[0].startswith("orders a") and "b" not in plans[0].split(" (")[0], plans
