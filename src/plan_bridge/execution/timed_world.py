"""A simulated world for temporal and numeric domains, with faults in durative actions.

:class:`TimedWorld` holds the true facts *and* the true numbers (``(battery r1)``).
A :class:`TimedSkill` plays one durative action against it: the at-start conditions
are checked (not yet the over-all ones: an action planned to start with the one that
establishes them may begin a moment earlier) and the at-start effects applied when it
starts, the action lasts its
duration on the world's simulated clock (:attr:`TimedWorld.clock`: no wall time unless
a ``time_scale`` paces it; a preempt ends the wait at once), then the over-all and
at-end conditions are checked on the true world and the at-end effects applied. It reports what it saw of
the atoms and numbers the action touches (numbers as numeric observations).

Faults, each with probability ``fail_rate x fault_scale[kind]``:

* ``late``: the action takes twice its planned duration;
* ``halfway``: it fails halfway: the at-end effects do not happen and the robot
  falls back to where it began (the at-start changes of facts are undone, energy
  spent stays spent);
* ``drift``: its numeric decreases are 1.5 times what the model says (a battery
  draining faster than modelled), which the belief learns from the observation.

The faults of a step are drawn from a generator of its own, seeded by the world's
seed, the step and how many times it began before: two robots' steps that start at
the same moment draw the same faults whichever thread comes first, so a seeded run
meets the same faults on the same steps every time.

Steps dispatched together take turns on the clock (see
:mod:`plan_bridge.execution.clock`): they begin, end and meet the world in the order of
their simulated times, ties broken by step index, so a seeded run of a temporal plan
is the same run every time, whatever the threads do.

Instantaneous actions of a temporal domain run as plain symbolic steps.
"""

from __future__ import annotations

import random
import threading
from collections.abc import Mapping
from typing import Any, ClassVar

import smach
from plan_bridge.belief import values_of
from plan_bridge.execution.semantics import GroundAction
from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = ["TimedSkill", "TimedWorld", "timed_skills"]

Reading = tuple[Fact, "bool | float"]


class TimedWorld(SimulatedWorld):
    """True facts and numbers of a temporal/numeric domain, with timed faults."""

    state: ClassVar[tuple[str, ...]] = ("_undo", "begun")
    constant: ClassVar[tuple[str, ...]] = ("seed",)
    wiring: ClassVar[tuple[str, ...]] = ("_drawing", "_count_lock")
    fault_scale: ClassVar[Mapping[str, float]] = {"late": 1.0, "halfway": 1.0, "drift": 1.0}
    #: How much faster a drifting numeric decrease is than modelled.
    drift_factor = 1.5

    def __init__(self, task: PlanningTask, *, seed: int | None = 0, **options: Any) -> None:
        if seed is None:  # an unseeded world still draws every step's faults from a seed
            seed = random.SystemRandom().randrange(2**63)
        super().__init__(task, seed=seed, **options)
        self.seed = seed
        #: Steps failing halfway -> (facts to add back, facts to remove) when they end.
        self._undo: dict[str, tuple[set[Fact], set[Fact]]] = {}
        #: Step (as PDDL text) -> how many times it began.
        self.begun: dict[str, int] = {}
        self._drawing = threading.local()
        self._count_lock = threading.Lock()

    def chance(self, kind: str, rng: random.Random | None = None) -> bool:
        # In begin(): the generator of the step beginning in this thread.
        return super().chance(kind, rng or getattr(self._drawing, "rng", None))

    @property
    def facts(self) -> frozenset[Fact]:
        with self._lock:
            return self.state_now()

    def goal_reached(self) -> bool:
        return self.model.goal_holds(self.facts)

    def begin(self, step: PlanStep) -> tuple[bool, set[str]]:
        """Start ``step``: (started?, faults drawn for it). A step that will fail
        halfway keeps its at-start effects in :attr:`_undo` until it ends."""
        ground = self.model.ground(step)
        with self._count_lock:
            n = self.begun.get(str(step), 0)
            self.begun[str(step)] = n + 1
        self._drawing.rng = random.Random(f"{self.seed}/{step}/{n}")
        try:
            return self._begin(step, ground)
        finally:
            self._drawing.rng = None

    def _begin(self, step: PlanStep, ground: GroundAction) -> tuple[bool, set[str]]:
        with self._lock:
            self.actions_run += 1
            state = self.state_now()
            # At-start conditions only: the over-all ones are checked when it ends
            # (a step planned to start with the one that establishes them may begin
            # a moment before it, as two robots would).
            if not ground.startable(state):
                return False, set()
            faults = {kind for kind in ("late", "halfway", "drift") if self.chance(kind)}
            for kind in sorted(faults):
                self.inject(kind, str(step))
            adds, dels, values = ground.start_effects(state)
            self._apply(adds, dels, values)
            # An action that does not end well (fails halfway, is preempted) leaves
            # the robot where it began (a drive returns to its start): the at-start
            # changes of facts are undone then; energy spent stays spent.
            self._undo[str(step)] = (set(dels - adds), set(adds - dels))
        return True, faults

    def _take_back(self, key: str) -> None:
        """Undo the at-start changes of facts of the step ``key`` (lock held)."""
        undo = self._undo.pop(key, None)
        if undo is not None:
            self._apply(undo[0], undo[1], {})

    def abandon(self, step: PlanStep) -> None:
        """``step`` stopped before its end: undo its at-start changes of facts."""
        with self._lock:
            self._take_back(str(step))

    def abandon_running(self) -> None:
        """Every step begun and not ended is abandoned, as by :meth:`abandon`.

        For a world restored from a checkpoint taken while steps were in progress: the
        process that ran them is gone, so they stopped where they were (a drive is back
        where it began) and a resumed run starts them again.
        """
        with self._lock:
            for key in list(self._undo):
                self._take_back(key)

    def finish(self, step: PlanStep, faults: set[str]) -> bool:
        """End ``step`` (its over-all and at-end conditions, at-end effects)."""
        ground = self.model.ground(step)
        with self._lock:
            state = self.state_now()
            if "halfway" in faults or ground.unmet_invariant(state) or ground.unmet_at_end(state):
                self._take_back(str(step))
                return False
            self._undo.pop(str(step), None)
            adds, dels, values = ground.end_effects(state)
            if "drift" in faults:
                before = values_of(state)
                values = {
                    atom: before[atom] - (before[atom] - value) * self.drift_factor
                    if atom in before and value < before[atom]
                    else value
                    for atom, value in values.items()
                }
            self._apply(adds, dels, values)
        return True

    def readings(self, ground: GroundAction) -> list[Reading]:
        """What a robot sees of the atoms and numbers ``ground`` touches."""
        with self._lock:
            return self._readings(ground, self.state_now())


class TimedSkill(smach.State):
    """Plays one (durative) action in a :class:`TimedWorld` (see the module doc)."""

    def __init__(self, world: TimedWorld, step: PlanStep) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"],
            input_keys=["duration", "end_ready", "begun"],
            output_keys=["observations"],
        )
        self.world = world
        self.step = step

    def execute(self, ud: smach.UserData) -> str:
        ground = self.world.model.ground(self.step)
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        started, faults = self.world.begin(self.step)
        if not started:
            ud.observations = self.world.readings(ground)
            return "aborted"
        ud.begun()  # the steps planned to start during this one may begin now
        duration = float(ud.duration or 0.0)
        if "late" in faults:
            duration *= 2.0
        if "halfway" in faults:
            duration /= 2.0
        if not self._wait(duration):
            self.world.abandon(self.step)
            ud.observations = self.world.readings(ground)
            self.service_preempt()
            return "preempted"
        if "halfway" not in faults:
            ud.end_ready()  # e.g. keep holding the door until the courier is through
        ok = self.world.finish(self.step, faults)
        ud.observations = self.world.readings(ground)
        return "succeeded" if ok else "aborted"

    def _wait(self, seconds: float) -> bool:
        """Let ``seconds`` of simulated time pass; False when preempted meanwhile."""
        return self.world.clock.sleep(seconds, self.preempt_requested)


def timed_skills(world: TimedWorld, registry: SkillRegistry | None = None) -> SkillRegistry:
    """A registry whose unregistered actions run as :class:`TimedSkill` in ``world``."""
    registry = registry or SkillRegistry()
    registry.fallback = lambda step: TimedSkill(world, step)
    registry.world = world
    return registry
