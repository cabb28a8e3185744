"""Skills and world of the timed courier mission.

Every action runs as a :class:`~plan_bridge.execution.timed_world.TimedSkill` in a
:class:`CourierWorld`: at-start effects when it starts, its planned duration (scaled
by the world's ``time_scale``), over-all and at-end conditions checked on the true
world, then at-end effects; it reports what it saw of the facts and numbers the
action touches (the battery level included). Faults (``--fail-rate``): an action
that runs late, one that fails halfway, a battery that drains faster than modelled.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from plan_bridge.execution.timed_world import TimedWorld, timed_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask

__all__ = ["CourierWorld", "setup"]


class CourierWorld(TimedWorld):
    """The courier's world: faults of every kind, drifts twice as likely (each step's
    faults drawn from its own seeded generator, as in every
    :class:`~plan_bridge.execution.timed_world.TimedWorld`)."""

    fault_scale: ClassVar[Mapping[str, float]] = {"late": 0.5, "halfway": 0.5, "drift": 1.0}


def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup:
    """The mission's skills and simulated world for one run."""
    world = CourierWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=timed_skills(world), world=world)
