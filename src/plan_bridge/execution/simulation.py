"""Symbolic skills: run any PDDL domain against a simulated world, with faults.

The simulated world holds the true facts. A symbolic skill applies its action's
effects to it when the action succeeds, and fails (changing nothing) with probability
``fail_rate``, drawn from a seeded random generator. Either way it reports what it
sees of the facts its action touches, so the executive's belief follows the world.
This makes any PDDL domain executable without writing skills.

Time belongs to the world: its :attr:`SimulatedWorld.clock` is a
:class:`~plan_bridge.execution.clock.SimClock`, which its skills' activities move on
(:meth:`SimulatedWorld.elapse`) without sleeping, unless a ``time_scale`` asks to pace
it for a viewer. Steps that run at the same time (a temporal plan's dispatch, a
Concurrence layer) take turns on it in simulated time, so a seeded run is a function of
its seed (see :mod:`plan_bridge.execution.clock`).
"""

from __future__ import annotations

import random
import threading
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import smach
from plan_bridge.belief import FactSnapshot, Observation
from plan_bridge.execution.clock import MAX_PACE_S, SimClock
from plan_bridge.execution.semantics import ActionModel, GroundAction
from plan_bridge.execution.snapshots import SnapshotError, decode, encode
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact, parse_fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = ["Fault", "SimulatedWorld", "SymbolicSkill", "symbolic_skills"]


@dataclass(frozen=True)
class Fault:
    """A fault the simulated world injected: when (simulated seconds), what, where."""

    time: float
    kind: str
    action: str
    detail: str = ""


class SimulatedWorld:
    """The true state of a simulated world, with seeded faults.

    Domain worlds subclass it: they keep the true PDDL facts in :attr:`_facts`
    (under :attr:`_lock`), advance :attr:`sim_time` (simulated robot seconds, the time
    of :attr:`clock`) as the robot acts (``self.sim_time += 2.0``, or :meth:`elapse`), draw their faults with :meth:`chance` and record every fault they
    inject with :meth:`inject`, so that runs can be compared (``plan-bridge study``).

    Every attribute of a world is declared once, in one of three class attributes
    (each class lists its own; a subclass adds to its bases'):

    * :attr:`state`: what changes while the world runs. :meth:`snapshot` saves all of
      it and :meth:`restore` puts all of it back, so a resumed run continues the
      same world;
    * :attr:`constant`: what is fixed when the world is made (read from the task);
    * :attr:`wiring`: live connections that are not the world (locks, subscribers).

    :meth:`snapshot` refuses a world with an attribute in none of them, naming it:
    a new attribute cannot be left out of checkpoints by mistake.
    """

    state: ClassVar[tuple[str, ...]] = (
        "_facts",
        "values",
        "sim_time",
        "actions_run",
        "faults",
        "rng",
    )
    constant: ClassVar[tuple[str, ...]] = ("task", "model", "fail_rate", "variant")
    wiring: ClassVar[tuple[str, ...]] = ("_lock", "clock")

    #: Simulated seconds one symbolic action takes.
    action_duration = 1.0
    #: Probability of each kind of fault per unit of ``fail_rate`` (see :meth:`chance`).
    fault_scale: ClassVar[Mapping[str, float]] = {}
    #: The variants of the world a domain offers (``plan-bridge study --variant``), such as
    #: a fault its scripted baseline was not written for; ``""`` is the ordinary world.
    variants: ClassVar[tuple[str, ...]] = ("",)

    def __init__(
        self,
        task: PlanningTask,
        *,
        seed: int | None = 0,
        fail_rate: float = 0.0,
        facts: Iterable[Fact] | None = None,
        variant: str = "",
    ) -> None:
        if variant not in self.variants:
            raise ValueError(f"unknown variant {variant!r}; variants: {', '.join(self.variants)}")
        if not 0.0 <= fail_rate <= 1.0:
            raise ValueError(f"fail_rate must be between 0 and 1, got {fail_rate}")
        self.task = task
        self.model = ActionModel(task)
        self.rng = random.Random(seed)
        self.fail_rate = fail_rate
        self.variant = variant
        self._facts: set[Fact] = set(task.initial_facts if facts is None else facts)
        #: Numeric atoms (as PDDL text, for snapshots) -> value; empty without numbers.
        self.values: dict[str, float] = {
            format_fact(atom): value for atom, value in self.model.initial_values().items()
        }
        #: The world's time (:attr:`sim_time` is its reading).
        self.clock = SimClock()
        self._lock = _PacedLock(self.clock)
        self.faults: list[Fault] = []
        self.actions_run = 0

    @property
    def time_scale(self) -> float:
        """Wall seconds per simulated second (``plan-bridge run --time-scale``): the
        clock's pace; 0: no waiting."""
        return self.clock.time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        if value < 0:
            raise ValueError(f"time_scale must be 0 or more, got {value!r}")
        self.clock.time_scale = float(value)

    @property
    def sim_time(self) -> float:
        """Simulated seconds: the time of :attr:`clock`. Adding to it is an activity
        of the calling thread that takes that long (:meth:`elapse`)."""
        return self.clock.now()

    @sim_time.setter
    def sim_time(self, value: float) -> None:
        seconds = float(value) - self.clock.now()
        if seconds >= 0:
            self.elapse(seconds)
        else:
            self.clock.reset(float(value))

    def elapse(self, seconds: float) -> None:
        """The calling thread's activity takes ``seconds`` of simulated time.

        A step taking turns on the clock (a temporal dispatch, a Concurrence layer)
        waits on the clock until it is that time, so the others act in between in
        simulated-time order; any other thread moves the clock on at once. With a
        :attr:`time_scale`, the wait is paced in wall time too. Called with the world's
        lock held (worlds move their clocks under it), the wait happens when the thread
        releases the lock, so other robots can use the world meanwhile.
        """
        if seconds <= 0:
            return
        clock = self.clock
        if self._lock.held():
            if not clock.taking_part():
                clock.advance(seconds)  # now: what happens next under the lock sees it
            self._lock.owe(seconds)
        elif clock.taking_part():
            clock.sleep(seconds)
        else:
            clock.advance(seconds)
            clock.pace(seconds)

    @property
    def faults_injected(self) -> int:
        return len(self.faults)

    def chance(self, kind: str, rng: random.Random | None = None) -> bool:
        """Draw whether a fault of ``kind`` happens now.

        Its probability is ``fail_rate x fault_scale[kind]``, at most 1, drawn from
        ``rng`` (default: the world's seeded :attr:`rng`). A probability of 0 draws
        nothing, so a run without faults uses no random numbers. Only decides: record
        the fault with :meth:`inject` where it happens.
        """
        probability = min(1.0, self.fail_rate * self.fault_scale[kind])
        return probability > 0.0 and (self.rng if rng is None else rng).random() < probability

    def inject(self, kind: str, action: str, detail: str = "", time: float | None = None) -> Fault:
        """Record a fault (call it where the world decides one happens).

        ``time`` defaults to :attr:`sim_time`; worlds with a clock per robot pass theirs.
        """
        fault = Fault(self.sim_time if time is None else time, kind, action, detail)
        self.faults.append(fault)
        return fault

    @classmethod
    def declared(cls, kind: str) -> tuple[str, ...]:
        """The attributes of ``kind`` (state, constant, wiring) of this class and its bases."""
        names: dict[str, None] = {}
        for klass in reversed(cls.__mro__):
            names.update(dict.fromkeys(klass.__dict__.get(kind, ())))
        return tuple(names)

    def undeclared(self) -> list[str]:
        """Attributes of this world that no declaration names (they would not be saved)."""
        known = {*self.declared("state"), *self.declared("constant"), *self.declared("wiring")}
        return sorted(name for name in vars(self) if name not in known)

    def snapshot(self) -> dict[str, Any]:
        """Every :attr:`state` attribute as JSON data (for checkpoints).

        Raises :class:`~plan_bridge.execution.snapshots.SnapshotError` if the world
        has an attribute that no declaration names, or a value that cannot be saved.
        """
        missing = self.undeclared()
        if missing:
            raise SnapshotError(
                f"{type(self).__name__}: attribute(s) {', '.join(missing)} declared nowhere; "
                f"add each to the class's `state` (saved in checkpoints), `constant` (fixed "
                f"when the world is made) or `wiring` (locks, subscribers)"
            )
        with self._lock:
            return {name: encode(getattr(self, name), name) for name in self.declared("state")}

    def restore(self, data: dict[str, Any]) -> None:
        """Put the world back into a :meth:`snapshot` state (all of it)."""
        names = self.declared("state")
        absent = [name for name in names if name not in data]
        if absent:
            raise SnapshotError(
                f"not a snapshot of a {type(self).__name__}: {', '.join(absent)} missing "
                f"(a checkpoint of another world, or of an older version)"
            )
        values = {name: decode(data[name], name) for name in names}
        with self._lock:
            for name, value in values.items():
                if name == "sim_time":
                    self.clock.reset(float(value))  # set, not advanced: nothing happens
                else:
                    object.__setattr__(self, name, value)

    def abandon_running(self) -> None:
        """Abandon the actions in progress (after :meth:`restore` into a new process,
        whose predecessor ran them). An action here happens at once, so none is ever
        in progress; a world with durative actions undoes their start."""

    def goal_reached(self) -> bool:
        """Whether the task's goal holds in the true world."""
        return self.model.goal_holds(self.facts)

    @property
    def facts(self) -> frozenset[Fact]:
        with self._lock:
            return frozenset(self._facts)

    def holds(self, *fact: str) -> bool:
        """Whether a fact is true in the world: ``world.holds("at", "pr2", "kitchen")``."""
        with self._lock:
            return fact in self._facts

    def perform(self, step: PlanStep) -> tuple[bool, list[tuple[Fact, bool | float]]]:
        """Try ``step`` in the world: (succeeded?, observations of the touched facts)."""
        ground = self.model.ground(step)
        with self._lock:
            self.actions_run += 1
            self.sim_time += self.action_duration
            # The live set, not a copy: worlds with many static facts would pay a copy
            # of all of them per action; with numbers, the facts with their values.
            state = self.state_now() if self.values else self._facts
            if self.values:
                adds, dels, values = ground.all_effects(state)
            else:
                (adds, dels), values = ground.effects(state), {}
            touched = ground.relevant_atoms(state, (adds, dels))
            ok = ground.applicable(state)
            if ok and self.fail_rate and self.rng.random() < self.fail_rate:
                self.inject("action-failed", str(step), "the action had no effect")
                ok = False
            if ok:
                self._apply(adds, dels, values)
            observations: list[tuple[Fact, bool | float]] = [
                (fact, fact in self._facts) for fact in sorted(touched)
            ]
            observations.extend(
                (atom, self.values[format_fact(atom)])
                for atom in sorted(values)
                if format_fact(atom) in self.values
            )
        return ok, observations

    # -- the World protocol (plan_bridge.execution.world.World) ---------------------------
    def now(self) -> float:
        return float(self.sim_time)

    def adopt(self, step: PlanStep, observations: Sequence[Observation]) -> None:
        """A skill that is not the world's own did ``step`` and succeeded: its declared
        effects become true (computed in the true state), then its observations."""
        ground = self.model.ground(step)
        with self._lock:
            self.actions_run += 1
            adds, dels, values = ground.all_effects(self.state_now())
            self._apply(adds, dels, values)
            for fact, value in observations:
                if isinstance(value, bool):
                    (self._facts.add if value else self._facts.discard)(fact)
                else:
                    self.values[format_fact(fact)] = value

    def sense(self, steps: Sequence[PlanStep]) -> list[Observation]:
        """The truth of the atoms and numbers ``steps`` read or change (what a robot
        looking at the places and things of those actions would see)."""
        with self._lock:
            state = self.state_now()
            seen: dict[Fact, bool | float] = {}
            for step in steps:
                seen.update(self._readings(self.model.ground(step), state))
        return sorted(seen.items(), key=lambda item: item[0])

    def _readings(self, ground: GroundAction, state: FactSnapshot) -> list[Observation]:
        """What a robot sees of the atoms and numbers ``ground`` touches in ``state``."""
        adds, dels, values = ground.all_effects(state)
        atoms = set(ground.precondition_atoms() or ()) | adds | dels
        out: list[Observation] = [(fact, fact in state) for fact in sorted(atoms)]
        out.extend((atom, state.values[atom]) for atom in sorted(values) if atom in state.values)
        return out

    def figures(self) -> dict[str, Any]:
        return {
            "sim_time_s": round(float(self.sim_time), 3),
            "faults_injected": self.faults_injected,
            "actions_run": self.actions_run,
        }

    def _apply(self, adds: set[Fact], dels: set[Fact], values: Mapping[Fact, float]) -> None:
        """Change the true facts and numbers (call with the lock held)."""
        self._facts.difference_update(dels)
        self._facts.update(adds)
        for atom, value in values.items():
            self.values[format_fact(atom)] = value

    def state_now(self) -> FactSnapshot:
        """The true facts and numbers (call with the lock held)."""
        return FactSnapshot(
            self._facts, {parse_fact(atom): value for atom, value in self.values.items()}
        )


class _PacedLock:
    """The world's lock; a thread that spent simulated time while holding it
    (:meth:`SimulatedWorld.elapse`) waits for it when it releases the lock, so that
    other threads can use the world meanwhile."""

    __slots__ = ("_clock", "_local", "_lock")

    def __init__(self, clock: SimClock) -> None:
        self._clock = clock
        self._lock = threading.Lock()
        self._local = threading.local()

    def owe(self, seconds: float) -> None:
        self._local.debt = getattr(self._local, "debt", 0.0) + seconds

    def held(self) -> bool:
        """Whether the calling thread holds the lock (through ``with``)."""
        return bool(getattr(self._local, "inside", False))

    def __enter__(self) -> bool:
        acquired = self._lock.acquire()
        self._local.inside = True
        return acquired

    def __exit__(self, *exc: object) -> None:
        self._local.inside = False
        self._lock.release()
        debt = getattr(self._local, "debt", 0.0)
        if debt > 0:
            self._local.debt = 0.0
            clock = self._clock
            if clock.taking_part():
                clock.sleep(debt)  # its turn ends until the clock gets there
            else:
                clock.pace(debt)  # (the clock moved on when the time was spent)

    def acquire(self, blocking: bool = True, timeout: float = -1) -> bool:
        return self._lock.acquire(blocking, timeout)

    def release(self) -> None:
        self._lock.release()

    def locked(self) -> bool:
        return self._lock.locked()


MAX_WAIT = MAX_PACE_S
"""The longest wall wait of one paced activity, seconds (a long charge stays watchable)."""


class SymbolicSkill(smach.State):
    """A skill that performs its action in a :class:`SimulatedWorld`."""

    def __init__(self, world: SimulatedWorld, step: PlanStep) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.world = world
        self.step = step

    def execute(self, ud: smach.UserData) -> str:
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        ok, observations = self.world.perform(self.step)
        ud.observations = observations
        return "succeeded" if ok else "aborted"


def symbolic_skills(world: SimulatedWorld, registry: SkillRegistry | None = None) -> SkillRegistry:
    """A registry whose unregistered actions run as symbolic skills in ``world``."""
    registry = registry or SkillRegistry()
    registry.fallback = lambda step: SymbolicSkill(world, step)
    registry.world = world
    return registry
