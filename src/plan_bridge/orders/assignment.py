"""Which steps of a plan serve which order, and which robots do them.

A plan made for several orders at once does not say which step is for which order.
:func:`order_work` reads it off the plan: an order's *achievers* are the steps that
add an atom of its goal; its robots are the agents of those steps; and a robot's
steps up to its last achiever of an order, after its previous order's, serve that
order (a robot's drive to the shelf serves the delivery it fetches for). Steps after
a robot's last achiever (a drive to the charger) serve no order.

The *agents* of a task (:func:`agents_of`) are the objects of the type most actions
take first (``?r - robot`` in ``(pick ?r ?o ?l)``), subtypes included: the robots of
the map domain, the PR2 of a PDDL domain.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from plan_bridge.execution.semantics import ActionModel
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.planning.types import PlanStep

__all__ = ["OrderWork", "agents_of", "order_work"]


@dataclass
class OrderWork:
    """What a plan does for one order: its robots and the positions of its steps."""

    robots: tuple[str, ...] = ()
    steps: set[int] = field(default_factory=set)
    """Positions in the plan (0-based) of the steps that serve the order."""


def agents_of(task: PlanningTask, objects: Mapping[str, str] | None = None) -> frozenset[str]:
    """The objects of the type most actions take as their first parameter (and of its
    subtypes), of ``objects`` (name -> type; default: the task's); empty for a task
    whose actions take no parameters."""
    firsts = Counter(
        schema.parameters[0].type for schema in task.actions.values() if schema.parameters
    )
    if not firsts:
        return frozenset()
    agent_type = firsts.most_common(1)[0][0]
    return frozenset(
        name
        for name, kind in (task.objects if objects is None else objects).items()
        if kind == agent_type or agent_type in task.type_ancestors.get(kind, ())
    )


def _agents(step: PlanStep, agents: frozenset[str]) -> tuple[str, ...]:
    found = tuple(arg for arg in step.arguments if arg in agents)
    return found or step.arguments[:1]


def order_work(
    plan: Sequence[PlanStep],
    orders: Mapping[str, Iterable[Fact]],
    model: ActionModel,
    facts: Iterable[Fact],
    agents: frozenset[str],
) -> dict[str, OrderWork]:
    """For each order (id -> goal atoms) that ``plan`` achieves from ``facts``, its
    robots and steps; an order whose atoms the plan does not add (they hold already)
    is left out."""
    goals = {order_id: frozenset(atoms) for order_id, atoms in orders.items()}
    state = set(facts)
    # In plan time (temporal plans are listed by start already; keep ties in order).
    positions = sorted(
        range(len(plan)), key=lambda i: (plan[i].start if plan[i].start is not None else i, i)
    )
    achievers: dict[str, list[int]] = {}
    for i in positions:
        adds, dels = model.ground(plan[i]).effects(frozenset(state))
        state -= dels
        state |= adds
        for order_id, goal in goals.items():
            if adds & goal:
                achievers.setdefault(order_id, []).append(i)
    work: dict[str, OrderWork] = {}
    # The last achiever of an order by each robot closes that robot's run of steps.
    closes: dict[str, dict[int, list[str]]] = {}
    for order_id, steps in achievers.items():
        robots = tuple(dict.fromkeys(r for i in steps for r in _agents(plan[i], agents)))
        work[order_id] = OrderWork(robots, set(steps))
        for robot in robots:
            last = max(i for i in steps if robot in _agents(plan[i], agents))
            closes.setdefault(robot, {}).setdefault(last, []).append(order_id)
    by_robot: dict[str, list[int]] = {}
    for i in positions:
        for robot in _agents(plan[i], agents):
            by_robot.setdefault(robot, []).append(i)
    for robot, ends in closes.items():
        run: list[int] = []
        for i in by_robot.get(robot, []):
            run.append(i)
            if i in ends:
                for order_id in ends[i]:
                    work[order_id].steps.update(run)
                run = []
    return work
