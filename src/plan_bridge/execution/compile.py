"""Compile a plan into a SMACH machine: one readable state per step.

Each step becomes a :class:`~plan_bridge.execution.steps.StepState` (a one-child
container around the skill, see :mod:`~plan_bridge.execution.steps`) labelled
``03_PICK_CUP_TABLE``. Sequential plans become a chain. With ``concurrent=True``, steps
that do not interfere (no step adds or deletes an atom the other needs or changes) are
grouped into layers, and each layer with several steps runs as a Concurrence:
independent actions of several robots run at the same time. A temporal plan becomes a
:class:`~plan_bridge.execution.temporal.TemporalDispatch`
(:func:`~plan_bridge.execution.temporal.compile_temporal`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import smach
from plan_bridge.belief import Belief
from plan_bridge.execution.clock import SimClock, Ticket, clock_of
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.steps import (
    STEP_OUTCOMES,
    CompiledPlan,
    PlanHold,
    StepOptions,
    StepRecord,
    StepState,
    build_steps,
)
from plan_bridge.execution.temporal import compile_temporal
from plan_bridge.execution.temporal_network import is_temporal
from plan_bridge.execution.world import World
from plan_bridge.pddl.task import Fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = ["TurnTakingConcurrence", "compile_plan"]


def compile_plan(
    steps: Sequence[PlanStep],
    skills: SkillRegistry,
    model: ActionModel,
    belief: Belief,
    *,
    first_index: int = 1,
    concurrent: bool = False,
    check_preconditions: bool = True,
    on_finished: Callable[[StepRecord], None] | None = None,
    variants: Mapping[int, str] | None = None,
    time_scale: float = 0.0,
    on_failure: str = "finish",
    world: World | None = None,
    on_started: Callable[[int, PlanStep], None] | None = None,
    hold: PlanHold | None = None,
) -> CompiledPlan:
    """Build the SMACH machine that executes ``steps`` (numbered from ``first_index``);
    ``variants`` maps a position in ``steps`` to the skill variant it runs; ``world``
    learns what the user's skills did (see :meth:`StepState._adopted`).

    A temporal plan (steps with start times) becomes a
    :class:`~plan_bridge.execution.temporal.TemporalDispatch` (``time_scale``: wall
    seconds per plan second; ``on_failure``: ``finish`` or ``preempt`` the steps still
    running when one fails); ``concurrent`` does not apply to it.

    ``on_started(index, step)`` is called when a step's skill starts; ``hold`` stops the
    plan from starting steps (:class:`PlanHold`).
    """
    steps = list(steps)
    options: StepOptions = {
        "first_index": first_index,
        "check_preconditions": check_preconditions,
        "on_finished": on_finished,
        "variants": variants,
        "world": world,
        "on_started": on_started,
        "hold": hold,
    }
    if is_temporal(steps):
        return compile_temporal(
            steps, skills, model, belief, time_scale=time_scale, on_failure=on_failure, **options
        )
    labels, states = build_steps(StepState, steps, skills, model, belief, options)
    layers = _layers(steps, model) if concurrent else [[i] for i in range(len(steps))]
    sm = smach.StateMachine(outcomes=list(STEP_OUTCOMES))
    sm.register_input_keys({k for s in states for k in s.get_registered_input_keys()})
    sm.register_output_keys({k for s in states for k in s.get_registered_output_keys()})
    if not steps:
        sm.add("00_GOAL_HOLDS", smach.CBState(lambda ud: "succeeded", outcomes=["succeeded"]))
        return CompiledPlan(sm, [], [], [], [])
    units: list[tuple[str, smach.State]] = []
    for layer in layers:
        if len(layer) == 1:
            units.append((labels[layer[0]], states[layer[0]]))
            continue
        input_keys = sorted({k for i in layer for k in states[i].get_registered_input_keys()})
        output_keys = sorted({k for i in layer for k in states[i].get_registered_output_keys()})
        clock = clock_of(world)
        group: smach.Concurrence
        if isinstance(clock, SimClock):
            keys = {labels[i]: i for i in layer}
            group = _TurnTakingLayer(clock, keys, input_keys, output_keys)
        else:
            group = smach.Concurrence(
                outcomes=list(STEP_OUTCOMES),
                default_outcome="succeeded",
                outcome_cb=_layer_outcome,
                input_keys=input_keys,
                output_keys=output_keys,
            )
        for i in layer:
            group.add(labels[i], states[i])
        number = labels[layer[0]].split("_", 1)[0]  # the first step's number
        units.append((f"{number}_PARALLEL_{len(layer)}", group))
    for n, (label, unit) in enumerate(units):
        following = units[n + 1][0] if n + 1 < len(units) else "succeeded"
        sm.add(label, unit, transitions={"succeeded": following})
    return CompiledPlan(sm, steps, labels, states, layers)


class TurnTakingConcurrence(smach.Concurrence):
    """A Concurrence whose children take turns on a simulated clock
    (:mod:`plan_bridge.execution.clock`): they run at once, but one at a time, the one
    due first in simulated time next (ties: by ``keys``, by default the order the
    children were added). Every child's place in the order is taken before any of them
    starts; run by a thread that takes turns on the clock already, the children run as
    in a plain Concurrence. The other arguments are :class:`smach.Concurrence`'s."""

    def __init__(
        self,
        clock: SimClock,
        outcomes: Sequence[str],
        default_outcome: str | None = None,
        *,
        keys: Mapping[str, int] | None = None,
        **options: Any,
    ) -> None:
        super().__init__(outcomes, default_outcome, **options)
        self.clock = clock
        self.keys = None if keys is None else dict(keys)
        self._tickets: dict[str, Ticket] = {}

    def run_children(self) -> str | None:
        clock = self.clock
        if clock.taking_part():  # run by a thread that takes turns already: as it is
            return super().run_children()
        keys = self.keys or {label: n for n, label in enumerate(self.get_children())}
        self._tickets = {label: clock.admit(key) for label, key in keys.items()}
        try:
            return super().run_children()
        finally:
            tickets, self._tickets = self._tickets, {}
            for ticket in tickets.values():
                clock.discard(ticket)

    def run_branch(self, label: str, body: Callable[[], None]) -> None:
        ticket = self._tickets.get(label)
        if ticket is None:
            body()
            return
        with self.clock.turn(ticket):
            body()


class _TurnTakingLayer(TurnTakingConcurrence):
    """A layer of steps on a simulated world's clock: they run at once and take turns
    on the clock (one at a time, in simulated-time order, ties broken by step index;
    see :mod:`plan_bridge.execution.clock`), so what one robot's step changes in the
    world or the belief reaches the other's in one order, run after run."""

    def __init__(
        self,
        clock: SimClock,
        keys: Mapping[str, int],
        input_keys: Sequence[str],
        output_keys: Sequence[str],
    ) -> None:
        super().__init__(
            clock,
            list(STEP_OUTCOMES),
            "succeeded",
            keys=keys,
            outcome_cb=_layer_outcome,
            input_keys=input_keys,
            output_keys=output_keys,
        )


def _layer_outcome(outcomes: dict[str, str | None]) -> str:
    values = set(outcomes.values())
    for worst in ("invalid", "aborted", "preempted"):
        if worst in values:
            return worst
    return "succeeded"


def _layers(steps: Sequence[PlanStep], model: ActionModel) -> list[list[int]]:
    """Group steps into layers of mutually independent steps, keeping causal order."""
    reads: list[frozenset[Fact] | None] = []
    writes: list[set[Fact]] = []
    for step in steps:
        ground = model.ground(step)
        pre = ground.precondition_atoms()
        adds, dels = ground.effects(frozenset())
        effects_all = {e.atom(ground._binding) for e in ground._lifted.effects}
        reads.append(pre)
        writes.append(adds | dels | effects_all)
    if any(r is None for r in reads):
        return [[i] for i in range(len(steps))]
    level = [0] * len(steps)
    for j in range(len(steps)):
        rj = reads[j] or frozenset()
        for i in range(j):
            ri = reads[i] or frozenset()
            if writes[i] & rj or writes[j] & ri or writes[i] & writes[j]:
                level[j] = max(level[j], level[i] + 1)
    layers: dict[int, list[int]] = {}
    for i, lvl in enumerate(level):
        layers.setdefault(lvl, []).append(i)
    return [layers[k] for k in sorted(layers)]
