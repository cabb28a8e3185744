"""Skills and world of the timed courier mission.

Every action runs as a :class:`~plan_bridge.execution.timed_world.TimedSkill` in a
:class:`CourierWorld`: at-start effects when it starts, its planned duration (scaled
by the world's ``time_scale``), over-all and at-end conditions checked on the true
world, then at-end effects; it reports what it saw of the facts and numbers the
action touches (the battery level included). Faults (``--fail-rate``): an action
that runs late, one that fails halfway, a battery that drains faster than modelled.
"""

from __future__ import annotations

import random
import threading
from collections.abc import Mapping
from typing import Any, ClassVar

from plan_bridge.execution.timed_world import TimedWorld, timed_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.planning.planner import PlanStep

__all__ = ["CourierWorld", "setup"]


class CourierWorld(TimedWorld):
    """The courier's world: faults of every kind, drifts twice as likely.

    The faults of a step are drawn from a generator of its own, seeded by the world's
    seed, the step and how many times it began before: two robots' steps that start
    at the same moment draw the same faults whichever thread comes first, so a seeded
    run meets the same faults every time (the study needs a run to be a function of
    its seed).
    """

    fault_scale: ClassVar[Mapping[str, float]] = {"late": 0.5, "halfway": 0.5, "drift": 1.0}
    state: ClassVar[tuple[str, ...]] = ("begun",)
    constant: ClassVar[tuple[str, ...]] = ("seed",)
    wiring: ClassVar[tuple[str, ...]] = ("_drawing", "_count_lock")

    def __init__(self, task: PlanningTask, *, seed: int = 0, **options: Any) -> None:
        super().__init__(task, seed=seed, **options)
        self.seed = seed
        #: Step (as PDDL text) -> how many times it began.
        self.begun: dict[str, int] = {}
        self._drawing = threading.local()
        self._count_lock = threading.Lock()

    def begin(self, step: PlanStep) -> tuple[bool, set[str]]:
        with self._count_lock:
            n = self.begun.get(str(step), 0)
            self.begun[str(step)] = n + 1
        self._drawing.rng = random.Random(f"{self.seed}/{step}/{n}")
        try:
            return super().begin(step)
        finally:
            self._drawing.rng = None

    def chance(self, kind: str, rng: random.Random | None = None) -> bool:
        return super().chance(kind, rng or getattr(self._drawing, "rng", None))


def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup:
    """The mission's skills and simulated world for one run."""
    world = CourierWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=timed_skills(world), world=world)
