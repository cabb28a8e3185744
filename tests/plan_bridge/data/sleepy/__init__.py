"""The rooms domain, except that a run at fault rate 1 hangs (for the study's run timeout)."""

from __future__ import annotations

import threading
from typing import Any

from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.missions.mission import MissionSetup


def setup(task: Any, *, seed: int, fail_rate: float) -> MissionSetup:
    if fail_rate >= 1.0:
        threading.Event().wait()  # a run that never returns
    world = SimulatedWorld(task, seed=seed, fail_rate=fail_rate)
    return MissionSetup(skills=symbolic_skills(world), world=world)
