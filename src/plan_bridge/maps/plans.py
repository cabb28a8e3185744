"""Plans of map tasks, tidied: a robot's drives one after the other become one.

Kairos' searches sometimes drive a robot to and fro before it does anything there
(numbers such as the battery make every visit a new state for a novelty search):
``navigate a b``, ``navigate b a``, ``navigate a b``... A robot's drives with none of its
other steps between them are one drive on the map: from the first one's start to the
last one's end (none when they end where they began), shorter than the detour (a
route is the shortest way) and lasting its route's length over the robot's speed.
:func:`tidied` merges them, starts every step as early as the plan's order allows
(:func:`~plan_bridge.execution.temporal_network.retimed`), and keeps the result only
if it is valid from the state and reaches the goal; else the plan as it came.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from plan_bridge.belief import FactSnapshot
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.temporal_network import is_temporal, retimed
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.planning.types import PlanStep

__all__ = ["tidied"]


def tidied(
    steps: Sequence[PlanStep], task: PlanningTask, state: FactSnapshot, model: ActionModel
) -> list[PlanStep]:
    """``steps`` (a plan of ``task`` from ``state``) with each robot's successive drives
    merged and the timeline closed up (see the module's doc)."""
    if not is_temporal(steps) or task.spec is None:
        return list(steps)
    values = dict(task.spec.values)
    merged = _merged(sorted(steps, key=lambda s: s.start or 0.0), task, values)
    if len(merged) == len(steps):
        return list(steps)
    durations = [_duration(step, values) for step in merged]
    candidate = retimed(merged, model, durations)
    return candidate if model.check_plan(candidate, state).valid else list(steps)


def _merged(
    steps: Sequence[PlanStep], task: PlanningTask, values: Mapping[Fact, float]
) -> list[PlanStep]:
    routes = {f[1:] for f in task.initial_facts if f[0] == "route"}
    kept: list[PlanStep | None] = []
    last_of: dict[str, int] = {}  # robot -> index in kept of its latest step
    for step in steps:
        robot = step.arguments[0] if step.arguments else ""
        index = last_of.get(robot, -1)
        before = kept[index] if index >= 0 else None
        if step.action == "navigate" and before is not None and before.action == "navigate":
            start, end = before.arguments[1], step.arguments[2]
            if start == end:
                kept[index] = None  # there and back: no drive at all
                del last_of[robot]
                continue
            if (start, end) in routes and ("metres", start, end) in values:
                kept[index] = PlanStep("navigate", (robot, start, end), before.start, None)
                continue
        kept.append(step)
        last_of[robot] = len(kept) - 1
    return [step for step in kept if step is not None]


def _duration(step: PlanStep, values: Mapping[Fact, float]) -> float | None:
    if step.action != "navigate" or step.duration is not None:
        return step.duration
    robot, start, end = step.arguments
    speed = values.get(("top-speed", robot), 0.0)
    return values[("metres", start, end)] / speed if speed > 0 else None
