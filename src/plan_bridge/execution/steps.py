"""A plan's steps as SMACH states, and what a compiled plan is.

Each step of a plan becomes a :class:`StepState` (a one-child container around the
skill) labelled ``03_PICK_CUP_TABLE``. Before running its skill it checks the action's
preconditions against the belief; when the skill succeeds it applies the action's
effects; it passes the skill's observations to the belief. Its outcomes are
``succeeded``, ``aborted``, ``preempted`` and ``invalid`` (preconditions unmet).
:func:`build_steps` makes the step states of a plan (of a class given: the temporal
dispatcher's steps are :class:`~plan_bridge.execution.timed_step.TimedStepState`);
:class:`CompiledPlan` is what :func:`~plan_bridge.execution.compile.compile_plan`
makes of them; :class:`PlanHold` stops a plan from starting steps.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypedDict, TypeVar

import smach
from plan_bridge.belief import Belief, Observation, describe_observation, normalise_observations
from plan_bridge.execution.clock import clock_of
from plan_bridge.execution.events import ObservationsApplied, StepFinished
from plan_bridge.execution.semantics import ActionModel, GroundAction
from plan_bridge.execution.world import World
from plan_bridge.pddl.task import Fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import (
    OBSERVATIONS_KEY,
    REQUIRED_OUTCOMES,
    STEP_KEYS,
    Skill,
    SkillRegistry,
)
from smach.introspection.events import Event, stamp

__all__ = [
    "STEP_OUTCOMES",
    "CompiledPlan",
    "PlanContainer",
    "PlanHold",
    "StepOptions",
    "StepRecord",
    "StepState",
    "build_steps",
    "step_label",
]

STEP_OUTCOMES = (*REQUIRED_OUTCOMES, "invalid")
S = TypeVar("S", bound="StepState")


@dataclass
class StepRecord:
    """What happened to one step in its last execution."""

    index: int
    step: PlanStep
    outcome: str = ""
    skill_outcome: str = ""
    unmet: tuple[str, ...] = ()
    observations_changed: tuple[str, ...] = ()
    duration_s: float = 0.0
    observed: bool = False
    """Whether the skill reported observations."""
    by_user: bool = False
    """Whether a user's own skill ran it (not a simulated one): when it fails without
    observing, the world is sensed around it before any replan."""


class PlanHold:
    """When a plan in force stops starting steps while its running steps finish.

    Held on :meth:`request` (from any thread), or once the run's clock reaches the time
    :attr:`alarm` gives (an order due to arrive). A held plan ends ``preempted`` with its
    unstarted steps not run; the executive then takes what asked for the hold (new
    orders, a cancel) and plans again. Unlike a preempt, no running step is stopped:
    a robot in the middle of a drive completes it.
    """

    def __init__(self) -> None:
        self._requested = threading.Event()
        self._lock = threading.Lock()
        self._pokes: list[Callable[[], None]] = []
        #: The clock time at which the plan holds (None: not before a request).
        self.alarm: Callable[[], float | None] | None = None

    def request(self) -> None:
        """Hold the plan in force (and the next one, until :meth:`clear`)."""
        self._requested.set()
        with self._lock:
            pokes = list(self._pokes)
        for poke in pokes:
            poke()

    def clear(self) -> None:
        self._requested.clear()

    def due(self) -> float | None:
        """The clock time of the alarm, if any."""
        return None if self.alarm is None else self.alarm()

    def held(self, now: float) -> bool:
        """Whether the plan holds at clock time ``now``."""
        if self._requested.is_set():
            return True
        due = self.due()
        return due is not None and due <= now + 1e-9

    def watch(self, poke: Callable[[], None]) -> None:
        """Call ``poke()`` on every :meth:`request` (a dispatcher waiting to start steps)."""
        with self._lock:
            self._pokes.append(poke)

    def unwatch(self, poke: Callable[[], None]) -> None:
        with self._lock:
            if poke in self._pokes:
                self._pokes.remove(poke)


def step_label(index: int, step: PlanStep, width: int = 2) -> str:
    """``03_PICK_CUP_TABLE``: readable, unique within a plan, safe in state paths."""
    words = [step.action, *step.arguments]
    text = "_".join(re.sub(r"[^A-Za-z0-9]+", "-", w).strip("-").upper() for w in words)
    return f"{index:0{width}d}_{text}"


class StepState(smach.Wrapper):
    """One plan step: precondition check, the skill, effects and observations."""

    extra_outcomes = ()
    #: The userdata keys the step gives its skill: they do not cross its boundary.
    provided_keys: tuple[str, ...] = STEP_KEYS

    def __init__(
        self,
        index: int,
        ground: GroundAction,
        belief: Belief,
        skill: Skill | None,
        *,
        check_preconditions: bool = True,
        on_finished: Callable[[StepRecord], None] | None = None,
        world: World | None = None,
        on_started: Callable[[int, PlanStep], None] | None = None,
        hold: PlanHold | None = None,
    ) -> None:
        super().__init__(outcomes=list(STEP_OUTCOMES), input_keys=[], output_keys=[])
        self.index = index
        self.ground = ground
        self.belief = belief
        self.skill = skill
        #: The world told about a user's skill that succeeded (:meth:`World.adopt`).
        self.world = world
        self.check_preconditions = check_preconditions
        self.on_finished = on_finished
        #: Called with the step's index and action when its skill is about to start.
        self.on_started = on_started
        #: The plan's hold: a sequential step held does not start (:class:`PlanHold`).
        self.hold = hold
        self.record = StepRecord(index, ground.step)
        self._set_up()

    def _set_up(self) -> None:
        """Called last by the constructor: a kind of step sets up what it keeps besides
        here (:class:`~plan_bridge.execution.timed_step.TimedStepState`), so that every
        kind is made with this constructor's arguments (:func:`build_steps`)."""

    def add(
        self, label: str, state: smach.State, remapping: Mapping[str, str] | None = None
    ) -> smach.State:
        added = super().add(label, state, remapping)
        remap = remapping or {}
        # Step keys are provided here; observations are consumed here: neither crosses
        # the step's boundary. Every other key the skill declares comes from the plan.
        self.register_input_keys(
            [
                remap.get(k, k)
                for k in state.get_registered_input_keys()
                if k not in self.provided_keys
            ]
        )
        self.register_output_keys(
            [remap.get(k, k) for k in state.get_registered_output_keys() if k != OBSERVATIONS_KEY]
        )
        return added

    def consistency_problems(self) -> list[str]:
        children = self.get_children()
        if not children:
            return [f"{self.path}: the step has no skill"]
        problems = []
        ((label, child),) = children.items()
        for outcome in child.get_registered_outcomes():
            mapped = self.skill.map_outcome(outcome) if self.skill else outcome
            if mapped not in REQUIRED_OUTCOMES:
                problems.append(
                    f"{self.path}/{label}: skill outcome {outcome!r} is not one of "
                    f"{', '.join(REQUIRED_OUTCOMES)} and is not mapped by the skill's outcome_map"
                )
        return problems

    def run(self, child: smach.State, label: str) -> str:
        record = StepRecord(self.index, self.ground.step)
        self.record = record
        if self.hold is not None and self.hold.held(clock_of(self.world).now()):
            return "preempted"  # not started: no record, the plan holds here
        started = time.monotonic()
        with self.belief.locked() as facts:
            if self.check_preconditions and not self.ground.applicable(facts):
                record.outcome = "invalid"
                record.unmet = tuple(self.ground.unmet_preconditions(facts))
                return self._finish(record, started)
            # Effects are those of the state the step starts in (conditional effects
            # read it), applied only if the skill succeeds.
            adds, dels = self.ground.effects(facts)
        self._started()
        self._give_step_keys()
        outcome, observations = self._skill_result(record, self.run_child(), label)
        if outcome == "succeeded":
            self.belief.apply(adds, dels)
            self._adopted(observations)
        self._observe(record, observations)
        record.outcome = outcome
        return self._finish(record, started)

    def _started(self) -> None:
        """The step's conditions held: its skill starts now."""
        if self.on_started is not None:
            self.on_started(self.index, self.ground.step)

    def _give_step_keys(self) -> smach.UserData:
        """Put the step's keys in its userdata for the skill (none of its observations
        yet); the userdata, for a subclass to add its own keys."""
        data = self.userdata
        data["action"] = self.ground.name
        data["arguments"] = self.ground.arguments
        data["params"] = self.ground.binding
        if OBSERVATIONS_KEY in data:
            del data[OBSERVATIONS_KEY]
        return data

    def _skill_result(
        self, record: StepRecord, skill_outcome: str, label: str
    ) -> tuple[str, list[Observation]]:
        """The step's outcome for its skill's ``skill_outcome`` (kept in ``record``),
        and what the skill observed (taken out of the userdata)."""
        record.skill_outcome = skill_outcome
        outcome = self.skill.map_outcome(skill_outcome) if self.skill else skill_outcome
        data = self.userdata
        raw = None
        if OBSERVATIONS_KEY in data:
            raw = data[OBSERVATIONS_KEY]
            del data[OBSERVATIONS_KEY]
        try:
            observations = normalise_observations(raw)
        except ValueError as exc:
            raise smach.InvalidUserCodeError(f"skill {self.path}/{label}: {exc}") from exc
        return outcome, observations

    def _adopted(self, observations: Sequence[Observation]) -> None:
        """A user's skill succeeded: the world learns what it did (a simulated world
        takes the declared effects; its own skills changed it themselves)."""
        if self.world is not None and self.skill is not None and not self.skill.simulated:
            self.world.adopt(self.ground.step, observations)

    def _observe(self, record: StepRecord, observations: Sequence[Observation]) -> None:
        """What the skill saw overrides the belief; the changes are an event."""
        record.observed = bool(observations)
        record.by_user = self.skill is not None and not self.skill.simulated
        changed = self.belief.observe(observations)
        record.observations_changed = tuple(
            describe_observation(fact, truth) for fact, truth in changed
        )
        if changed:
            self._announce(ObservationsApplied, changed=record.observations_changed)

    def _announce(self, kind: Callable[..., Event], **fields: Any) -> None:
        """Emit this step's event ``kind`` with ``fields`` (its path, the time and the
        thread filled in), if anybody listens."""
        if self.is_observed():
            t, thread = stamp()
            self.emit_event(kind(path=self.path, time=t, thread=thread, **fields))

    def _finish(self, record: StepRecord, started: float) -> str:
        record.duration_s = time.monotonic() - started
        self._announce(
            StepFinished,
            index=record.index,
            action=str(record.step),
            outcome=record.outcome,
            skill_outcome=record.skill_outcome,
            duration_s=record.duration_s,
        )
        if self.on_finished is not None:
            self.on_finished(record)
        return record.outcome


class PlanContainer(smach.Container):
    """A container whose children come from a plan, not from initial states: setting
    the initial state passes the userdata in only."""

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: smach.UserData | None = None
    ) -> None:
        if userdata is not None:
            self.userdata.update(userdata)


@dataclass
class CompiledPlan:
    """A plan as a SMACH machine, with its step states in plan order."""

    machine: smach.Container
    """A StateMachine (sequential plans), or a TemporalDispatch (temporal plans)."""
    steps: list[PlanStep]
    labels: list[str]
    step_states: list[StepState]
    layers: list[list[int]] = field(default_factory=list)
    settled_facts: Callable[[], frozenset[Fact]] | None = None
    """What a checkpoint keeps of the belief while steps are in progress (temporal
    plans: :meth:`~plan_bridge.execution.temporal.TemporalDispatch.settled_facts`);
    None: the belief as it is (a sequential step changes it only when it ends)."""


class StepOptions(TypedDict, total=False):
    """How :func:`build_steps` makes the step states of a plan (the keyword arguments of
    :func:`~plan_bridge.execution.compile.compile_plan` that are about its steps)."""

    first_index: int
    """The number of the plan's first step (1)."""
    check_preconditions: bool
    on_finished: Callable[[StepRecord], None] | None
    variants: Mapping[int, str] | None
    """A position in the plan -> the skill variant the step there runs."""
    world: World | None
    on_started: Callable[[int, PlanStep], None] | None
    hold: PlanHold | None


def build_steps(
    state_class: type[S],
    steps: Sequence[PlanStep],
    skills: SkillRegistry,
    model: ActionModel,
    belief: Belief,
    options: StepOptions,
) -> tuple[list[str], list[S]]:
    """The labels and the step states (of ``state_class``, each around its skill) of a
    plan, made as ``options`` say (what they leave out: :class:`StepState`'s defaults)."""
    first_index = options.get("first_index", 1)
    variants = options.get("variants") or {}
    width = max(2, len(str(first_index + len(steps))))
    labels = [step_label(first_index + i, s, width) for i, s in enumerate(steps)]
    states: list[S] = []
    for i, step in enumerate(steps):
        skill_state, skill = skills.create(step, variants.get(i))
        state = state_class(
            first_index + i,
            model.ground(step),
            belief,
            skill,
            check_preconditions=options.get("check_preconditions", True),
            on_finished=options.get("on_finished"),
            world=options.get("world"),
            on_started=options.get("on_started"),
            hold=options.get("hold"),
        )
        state.add("SKILL", skill_state)
        states.append(state)
    return labels, states
