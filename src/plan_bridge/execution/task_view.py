"""What the planner sees of the belief: a task made for the belief and the goal.

Most missions plan one task from start to end: its objects are fixed, the belief is
its facts. A world with a map is different: the belief knows the whole building
(every hallway open or closed, where every object lies), but a plan needs only the
places its task touches, and routes between them that depend on which hallways are
open. A :class:`TaskView` makes that task from the belief: the executive asks it for
the task before the first plan and before every recovery (a failure changed the
belief: a robot stopped somewhere else, a hallway was found closed), and plans the
task it gets. When the task is another one, the belief's **map atoms** (the facts and
numbers the view owns: routes and their lengths) are those of the new task.

The belief may thus hold facts of objects the task does not have; :func:`project`
gives the planner only those of the task's objects.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from typing import Protocol, runtime_checkable

from plan_bridge.belief import Belief, FactSnapshot, values_of
from plan_bridge.pddl.task import Fact, PlanningTask

__all__ = ["TaskView", "adopt_map_atoms", "project"]


@runtime_checkable
class TaskView(Protocol):
    """Makes the task to plan from a belief (see the module's doc)."""

    map_predicates: frozenset[str]
    """The predicates whose facts the view owns (lower case)."""
    map_functions: frozenset[str]
    """The numeric functions whose values the view owns (lower case)."""

    def belief(self) -> FactSnapshot:
        """What is believed at the start, of every object of the world (facts and
        values); the first task's map atoms are added to it."""
        ...

    def objects(self, facts: Collection[Fact] | None = None) -> Mapping[str, str]:
        """Every object of the world and its type (lower case); with ``facts`` (a
        belief), objects they have that the world did not know (seen on the way) too."""
        ...

    def task_for(self, facts: FactSnapshot, goal: Sequence[Fact]) -> PlanningTask:
        """The task for the belief ``facts`` and the goal atoms ``goal``: the same task
        object as before when nothing it holds changed."""
        ...


def adopt_map_atoms(
    view: TaskView, belief: Belief, task: PlanningTask, initial_values: Mapping[Fact, float]
) -> None:
    """Put ``task``'s map atoms (its facts, and of ``initial_values``, its initial
    numbers) into the belief in place of those it held; numbers the belief does not
    have yet come from ``initial_values`` too."""
    facts = belief.facts
    kept = {f for f in facts if f[0] not in view.map_predicates}
    kept |= {f for f in task.initial_facts if f[0] in view.map_predicates}
    values = {a: v for a, v in values_of(facts).items() if a[0] not in view.map_functions}
    values.update(
        (a, v) for a, v in initial_values.items() if a[0] in view.map_functions or a not in values
    )
    belief.replace(kept, values)


def project(facts: FactSnapshot, task: PlanningTask) -> FactSnapshot:
    """The facts and values of ``facts`` about the task's objects and symbols only."""
    objects = task.objects
    known = task.predicates
    functions = task.functions
    kept = [f for f in facts if f[0] in known and _all_in(f[1:], objects)]
    values = {
        a: v for a, v in values_of(facts).items() if a[0] in functions and _all_in(a[1:], objects)
    }
    return FactSnapshot(kept, values)


def _all_in(names: Sequence[str], objects: Collection[str]) -> bool:
    return all(name in objects for name in names)
