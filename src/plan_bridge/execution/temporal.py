"""Temporal plans as SMACH: one dispatcher container, actions started on events.

A time-triggered plan (each step with a planned ``start`` and ``duration``) compiles
into a :class:`TemporalDispatch`: a ``smach`` container whose children are
:class:`TimedStepState` steps, run concurrently in their own threads, like a
Concurrence whose children start at different times.

**When a step starts.** Before the run, the plan is turned into a simple temporal
network over the steps' start and end points (:func:`precedence`): a step *depends*
on an earlier one when one writes an atom (or a number) the other reads or writes.
A dependent step waits for the earlier step's **end** when the plan starts it after
that end, else for its **start** (the two overlap in the plan); in both cases it also
waits the planned lag between those points, times ``time_scale`` (wall seconds per
plan second). With ``time_scale > 0`` no step starts before its planned time on the
wall clock either (``t0 + start x time_scale``), so a simulated run plays the plan's
timeline. A step whose predecessors have happened starts only when its at-start
conditions hold in the belief; while other steps run it waits for them (the belief
may still change), and when nothing runs it starts anyway and reports ``invalid``.
So a late action delays its dependents instead of breaking them, and independent
actions planned with it go ahead; those planned after it wait with it (the plan is
broken there: the replan comes when the steps running end, instead of after another
robot's steps were played to the plan's end).

**Whose clock.** The dispatcher follows a :class:`~plan_bridge.execution.clock.Clock`:
the wall clock by default (a robot), or a simulated world's clock. On a simulated clock
plan seconds are the clock's seconds: no step starts before its planned time, lags
included (the clock's own ``time_scale`` paces it for a viewer, or it jumps), and the
dispatcher and every step's thread take turns on it (one runs at a time; the next is
the one due first in simulated time, ties broken by step index, the dispatcher
first). Ends that fall at the same simulated instant are thus met in one order, and a
seeded simulated run is a function of its seed.

**While a step runs.** At-start effects (and numeric ones) reach the belief when it
starts; its over-all conditions are checked on every change of the belief (a belief
listener, no polling) and a violation preempts its skill: the step ends ``aborted``
naming the condition. When the skill succeeds, the at-end conditions are checked and
the at-end effects applied, computed in the belief of that moment (a battery drained
meanwhile by another action is decreased from its current value). Skills receive the
planned duration in ``ud.duration`` (plan seconds) besides the usual step keys,
``ud.end_ready``: a callable that returns once the plan lets the step end, and
``ud.begun``: a callable a skill that declares it as an input key calls once its
action has begun (the robot took it up); a step's *start point*, which the steps
planned to start during it wait for, is that call, or for a skill without it the
moment its skill starts. (A door held open at the start of one step is open before
the step that passes through it begins, whichever thread runs first.)

**When a step ends.** A step's end waits for the points planned before it of the
steps it interferes with, and for the end of an interfering step nested in it that is
planned to end at the same instant (:func:`end_precedence`): a door held for a robot
passing through is not released before the robot is through, however quick the
holding skill. The wait happens when the skill calls ``ud.end_ready()`` (a skill holding
something calls it before letting go) and in any case before the at-end effects
reach the belief.

**Failure.** The first step that ends other than ``succeeded`` stops new starts. The
policy ``on_failure`` says what happens to the steps still running: ``"finish"``
(default: their effects are real, a robot in the middle of a move completes it, and
the belief stays consistent with what happened) or ``"preempt"``. The container then
ends with that step's outcome, and the executive above validates, repairs or replans
from the belief as for sequential plans.

Events: every step emits :class:`ActionStarted` and :class:`ActionEnded` with its
planned and actual (wall, since the dispatch began) times, on the same stream as
every other event: journal, viewer timeline and study read the same records.

(Over 600 lines: the temporal network, the timed step and the dispatcher that runs
them are one mechanism; its invariants about start and end points are read together.)
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import smach
from plan_bridge.execution.clock import WALL_CLOCK, Clock, Ticket, clock_of
from plan_bridge.execution.compile import (
    STEP_OUTCOMES,
    CompiledPlan,
    StepRecord,
    StepState,
    step_label,
)
from plan_bridge.execution.semantics import ActionModel, GroundAction
from plan_bridge.execution.world import World, WorldState, normalise_observations
from plan_bridge.pddl.task import Fact
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import OBSERVATIONS_KEY, STEP_KEYS, SkillRegistry
from smach.introspection.events import Event, stamp

__all__ = [
    "BEGUN_KEY",
    "DURATION_KEY",
    "END_READY_KEY",
    "ActionEnded",
    "ActionStarted",
    "Edge",
    "TemporalDispatch",
    "TimedStepState",
    "TimelineRecorder",
    "compile_temporal",
    "end_precedence",
    "is_temporal",
    "precedence",
]

#: Userdata key holding a step's planned duration (plan seconds) for its skill.
DURATION_KEY = "duration"
#: Userdata key of a callable a skill may call before it ends its action in the
#: world: it returns once the plan allows this step to end (a door is held until
#: the robot passing through it is through).
END_READY_KEY = "end_ready"
#: Userdata key of a callable a skill that declares it calls once its action has begun
#: in the world: the step's start point, for the steps that wait for it.
BEGUN_KEY = "begun"
_TIMED_STEP_KEYS = (*STEP_KEYS, DURATION_KEY, END_READY_KEY, BEGUN_KEY)
#: Plan times closer than this are the same instant (engines separate by epsilon).
EPSILON = 1e-6
POLICIES = ("finish", "preempt")


def is_temporal(steps: Sequence[PlanStep]) -> bool:
    """Whether ``steps`` is a time-triggered plan (its steps carry start times)."""
    return any(step.start is not None for step in steps)


@dataclass(slots=True, kw_only=True)
class ActionStarted(Event):
    """A step of a temporal plan started (``path`` is the step's state)."""

    kind: ClassVar[str] = "action_started"
    index: int
    action: str
    planned_start: float
    planned_duration: float
    actual_start: float
    """Wall seconds since the dispatch began."""
    time_scale: float = 0.0
    """Wall seconds per plan second of the dispatch (0: as fast as it goes)."""


@dataclass(slots=True, kw_only=True)
class ActionEnded(Event):
    """A step of a temporal plan ended (``path`` is the step's state)."""

    kind: ClassVar[str] = "action_ended"
    index: int
    action: str
    outcome: str
    planned_start: float
    planned_duration: float
    actual_start: float
    actual_end: float


class TimelineRecorder:
    """A listener for the makespans of a run: planned (of the first temporal plan) and
    executed (wall seconds from the first action's start to the last one's end)."""

    def __init__(self) -> None:
        self.makespan_planned: float | None = None
        self._first: float | None = None
        self._last: float | None = None

    def __call__(self, event: Event) -> None:
        from plan_bridge.execution.events import PlanComputed

        if isinstance(event, PlanComputed):
            if self.makespan_planned is None and event.makespan is not None:
                self.makespan_planned = event.makespan
        elif isinstance(event, ActionStarted):
            if self._first is None:
                self._first = event.time
        elif isinstance(event, ActionEnded):
            self._last = event.time

    @property
    def temporal(self) -> bool:
        return self.makespan_planned is not None

    @property
    def makespan_executed(self) -> float | None:
        if self._first is None or self._last is None:
            return None
        return self._last - self._first


# -- the temporal network ------------------------------------------------------------------


@dataclass(frozen=True)
class Edge:
    """Step ``after`` waits for the ``point`` (``start``/``end``) of step ``before``
    and then ``lag`` plan seconds."""

    before: int
    after: int
    point: str
    lag: float


class _Recorder(set[Fact]):
    """A state that records which atoms and numbers a condition reads."""

    def __init__(self, answer: bool) -> None:
        super().__init__()
        self.answer = answer
        self.read: set[Fact] = set()
        self.values = _RecordingValues(self.read)

    def __contains__(self, fact: object) -> bool:
        if isinstance(fact, tuple):
            self.read.add(fact)
        return self.answer


class _RecordingValues(Mapping[Fact, float]):
    def __init__(self, read: set[Fact]) -> None:
        self.read = read

    def __getitem__(self, key: Fact) -> float:
        self.read.add(key)
        return 1.0

    def __iter__(self) -> Iterator[Fact]:
        return iter(())

    def __len__(self) -> int:
        return 0


def _footprint(ground: GroundAction) -> tuple[set[Fact], set[Fact]]:
    """(atoms read, atoms written) by an action, numbers included (conservatively:
    both outcomes of every test are explored once)."""
    reads: set[Fact] = set()
    writes: set[Fact] = set()
    for answer in (True, False):
        state = _Recorder(answer)
        ground.applicable(state)
        ground.unmet_preconditions(state)
        ground.unmet_invariant(state)
        ground.unmet_at_end(state)
        adds, dels, values = ground.all_effects(state)
        reads |= state.read
        writes |= adds | dels | set(values)
    return reads, writes


Footprint = tuple[set[Fact], set[Fact]]


def footprints(steps: Sequence[PlanStep], model: ActionModel) -> list[Footprint]:
    """The (read, written) atoms of each step, for :func:`precedence` and
    :func:`end_precedence` (computing them is most of compiling a temporal plan)."""
    return [_footprint(model.ground(step)) for step in steps]


def end_precedence(
    steps: Sequence[PlanStep], model: ActionModel, prints: Sequence[Footprint] | None = None
) -> list[list[Edge]]:
    """For each step, the points its *end* waits for: the start and end points of the
    interfering steps planned before its end, and the end of an interfering step that
    began after it and is planned to end with it (a light held for an inspection is not
    switched off before the inspection ends, however quick the holding skill)."""
    prints = footprints(steps, model) if prints is None else prints
    starts = [step.start or 0.0 for step in steps]
    ends = [(step.start or 0.0) + (step.duration or 0.0) for step in steps]
    waits: list[list[Edge]] = [[] for _ in steps]
    for i in range(len(steps)):
        reads_i, writes_i = prints[i]
        for j in range(len(steps)):
            reads_j, writes_j = prints[j]
            if i == j or not (writes_i & (reads_j | writes_j) or writes_j & reads_i):
                continue
            nested = starts[j] > starts[i] + EPSILON  # j began while i was under way
            for point, at in (("start", starts[j]), ("end", ends[j])):
                before = at < ends[i] - EPSILON and (point == "end" or nested)
                # A step nested in this one and planned to end at the same instant ends
                # first (PDDL's over-all conditions need not hold at the end point): the
                # door is let go once the robot passing through is through.
                together = point == "end" and nested and at <= ends[i] + EPSILON
                if before or together:
                    waits[i].append(Edge(j, i, point, 0.0))
    return waits


def precedence(
    steps: Sequence[PlanStep], model: ActionModel, prints: Sequence[Footprint] | None = None
) -> list[list[Edge]]:
    """For each step, the edges its start waits for (see the module documentation)."""
    prints = footprints(steps, model) if prints is None else prints
    starts = [step.start or 0.0 for step in steps]
    ends = [(step.start or 0.0) + (step.duration or 0.0) for step in steps]
    order = sorted(range(len(steps)), key=lambda i: (starts[i], i))
    waits: list[list[Edge]] = [[] for _ in steps]
    for position, j in enumerate(order):
        reads_j, writes_j = prints[j]
        for i in order[:position]:
            reads_i, writes_i = prints[i]
            if not (writes_i & (reads_j | writes_j) or writes_j & reads_i):
                continue
            if starts[j] >= ends[i] - EPSILON:
                waits[j].append(Edge(i, j, "end", max(0.0, starts[j] - ends[i])))
            else:
                waits[j].append(Edge(i, j, "start", max(0.0, starts[j] - starts[i])))
    return waits


# -- one durative step ---------------------------------------------------------------------


@dataclass
class Timing:
    """Planned and actual times of one step (actual: wall seconds since dispatch)."""

    planned_start: float
    planned_duration: float
    actual_start: float | None = None
    actual_end: float | None = None


class TimedStepState(StepState):
    """A step of a temporal plan: at-start checks and effects when it starts, over-all
    conditions watched while its skill runs, at-end checks and effects on success."""

    def __init__(
        self,
        index: int,
        ground: GroundAction,
        belief: WorldState,
        skill: Any,
        *,
        check_preconditions: bool = True,
        on_finished: Callable[[StepRecord], None] | None = None,
        world: World | None = None,
    ) -> None:
        super().__init__(
            index,
            ground,
            belief,
            skill,
            check_preconditions=check_preconditions,
            on_finished=on_finished,
            world=world,
        )
        step = ground.step
        self.timing = Timing(step.start or 0.0, step.duration or 0.0)
        self.clock: Callable[[], float] = time.monotonic
        #: The dispatch's wall seconds per plan second (told to the viewer's timeline).
        self.time_scale = 0.0
        #: Called when the skill succeeded, before the end point: the dispatcher
        #: holds the end until the points planned before it have happened.
        self.before_end: Callable[[], None] | None = None
        #: Called once at the step's start point (see :data:`BEGUN_KEY`).
        self.on_begun: Callable[[], None] | None = None
        #: Called with the outcome when the step fails, before what it observed
        #: reaches the belief: no step is started on the strength of those
        #: observations after the failure that stops new starts.
        self.on_failed: Callable[[str], None] | None = None
        self._begun_once = threading.Lock()
        self._has_begun = False
        #: Held from reading the belief to applying the effects computed from it (the
        #: dispatch shares one between its steps): two steps increasing the same
        #: number at once must not both add to the old value.
        self.effects_lock = threading.Lock()
        #: While the step is in progress (its at-start effects in the belief, its at-end
        #: ones not yet): (facts its start removed, facts its start added), what undoing
        #: it would restore; None otherwise. Read and written under ``effects_lock``.
        self.in_flight: tuple[frozenset[Fact], frozenset[Fact]] | None = None
        self._violation: list[str] = []

    def add(
        self, label: str, state: smach.State, remapping: Mapping[str, str] | None = None
    ) -> smach.State:
        added = super(StepState, self).add(label, state, remapping)
        remap = remapping or {}
        # As StepState.add, with the planned duration provided here as well.
        self.register_input_keys(
            [
                remap.get(k, k)
                for k in state.get_registered_input_keys()
                if k not in _TIMED_STEP_KEYS
            ]
        )
        self.register_output_keys(
            [remap.get(k, k) for k in state.get_registered_output_keys() if k != OBSERVATIONS_KEY]
        )
        return added

    def run(self, child: smach.State, label: str) -> str:
        record = StepRecord(self.index, self.ground.step)
        self.record = record
        self._violation = []
        started = time.monotonic()
        ground = self.ground
        with self.effects_lock:
            with self.belief.locked() as facts:
                startable = not self.check_preconditions or ground.applicable(facts)
                if startable:
                    adds, dels, values = ground.start_effects(facts)
                    removed = frozenset(f for f in dels if f in facts and f not in adds)
                    added = frozenset(f for f in adds if f not in facts)
                else:
                    record.unmet = tuple(ground.unmet_preconditions(facts))
            if startable:
                self.belief.apply(adds, dels)
                self.belief.set_values(values)
                self.in_flight = (removed, added)
        if not startable:  # (outside the lock: finishing may write a checkpoint, which takes it)
            record.outcome = "invalid"
            return self._finish(record, started)
        try:
            return self._run_started(child, label, record, started)
        finally:
            with self.effects_lock:  # a failed step: its observations are in the belief
                self.in_flight = None

    def _run_started(
        self, child: smach.State, label: str, record: StepRecord, started: float
    ) -> str:
        ground = self.ground
        self._started()
        data = self._userdata._data
        data["action"] = ground.name
        data["arguments"] = ground.arguments
        data["params"] = ground.binding
        data[DURATION_KEY] = self.timing.planned_duration
        data[END_READY_KEY] = self._end_ready
        data[BEGUN_KEY] = self._begun
        self._has_begun = False
        data.pop(OBSERVATIONS_KEY, None)
        watch = self._watch(child)
        self.belief.add_listener(watch)
        try:
            watch()  # the start effects may already break the invariant
            if BEGUN_KEY not in child.get_registered_input_keys():
                self._begun()  # a skill that does not tell: it begins now
            try:
                skill_outcome = self.run_child()
            finally:
                self._begun()  # a skill that returned without telling (it failed to begin)
            if self.before_end is not None and not self._violation:
                self.before_end()
        finally:
            self.belief.remove_listener(watch)
        record.skill_outcome = skill_outcome
        outcome = self.skill.map_outcome(skill_outcome) if self.skill else skill_outcome
        try:
            observations = normalise_observations(data.pop(OBSERVATIONS_KEY, None))
        except ValueError as exc:
            raise smach.InvalidUserCodeError(f"skill {self._path}/{label}: {exc}") from exc
        if self._violation:
            outcome = "aborted"
            record.unmet = ("over all: " + ", ".join(self._violation),)
        elif outcome == "succeeded":
            with self.effects_lock:
                with self.belief.locked() as facts:
                    unmet = ground.unmet_at_end(facts)
                    end = ground.end_effects(facts) if not unmet else (set(), set(), {})
                if not unmet:
                    self.belief.apply(end[0], end[1])
                    self.belief.set_values(end[2])
                    self.in_flight = None  # with its end effects, atomically
            if unmet:
                outcome = "aborted"
                record.unmet = ("at end: " + ", ".join(unmet),)
            else:
                self._adopted(observations)
        if outcome != "succeeded":
            if self.on_failed is not None:
                self.on_failed(outcome)
            self._take_back()
        self._observe(record, observations)
        record.outcome = outcome
        self._ended(outcome)
        return self._finish(record, started)

    def _take_back(self) -> None:
        """A step that did not end well undid its start (a robot stopped mid-drive is
        back where it began): its at-start changes of facts leave the belief; what
        its skill observed (applied next) wins. Numbers it spent stay spent."""
        with self.effects_lock:
            if self.in_flight is not None:
                removed, added = self.in_flight
                self.belief.apply(removed, added)
                self.in_flight = None

    def _end_ready(self) -> None:
        if self.before_end is not None and not self._violation:
            self.before_end()

    def _begun(self) -> None:
        with self._begun_once:
            if self._has_begun:
                return
            self._has_begun = True
        if self.on_begun is not None:
            self.on_begun()

    def _watch(self, child: smach.State) -> Callable[[], None]:
        """A belief listener: preempt the skill when an over-all condition breaks."""
        ground = self.ground
        if not ground._lifted.invariant_parts:
            return lambda: None

        def check() -> None:
            if self._violation:
                return
            unmet = ground.unmet_invariant(self.belief.facts)
            if unmet:
                self._violation = unmet
                child.request_preempt()

        return check

    def _started(self) -> None:
        self.timing.actual_start = self.clock()
        self.timing.actual_end = None
        if self._bus.listeners:
            t, thread = stamp()
            self._bus.emit(
                ActionStarted(
                    path=self._path,
                    time=t,
                    thread=thread,
                    index=self.index,
                    action=str(self.ground.step),
                    planned_start=self.timing.planned_start,
                    planned_duration=self.timing.planned_duration,
                    actual_start=self.timing.actual_start,
                    time_scale=self.time_scale,
                )
            )

    def _ended(self, outcome: str) -> None:
        self.timing.actual_end = self.clock()
        if self._bus.listeners:
            t, thread = stamp()
            self._bus.emit(
                ActionEnded(
                    path=self._path,
                    time=t,
                    thread=thread,
                    index=self.index,
                    action=str(self.ground.step),
                    outcome=outcome,
                    planned_start=self.timing.planned_start,
                    planned_duration=self.timing.planned_duration,
                    actual_start=self.timing.actual_start or 0.0,
                    actual_end=self.timing.actual_end,
                )
            )


# -- the dispatcher ------------------------------------------------------------------------


@dataclass
class _Dispatch:
    """The state of one run of a :class:`TemporalDispatch`."""

    t0: float
    waiting: list[int]
    running: dict[int, threading.Thread] = field(default_factory=dict)
    started: dict[int, float] = field(default_factory=dict)
    ended: dict[int, float] = field(default_factory=dict)
    outcomes: dict[int, str] = field(default_factory=dict)
    failure: str | None = None
    errors: list[BaseException] = field(default_factory=list)
    holding: set[int] = field(default_factory=set)
    """Steps whose skills are done and whose ends wait for points not yet happened."""
    released: set[int] = field(default_factory=set)
    """Held steps let go because nothing else could happen: every running step was
    held and no step could start (a step the plan needs first cannot start), so the
    plan's order cannot be kept; their ends go ahead and the failure shows."""
    blocked: set[int] = field(default_factory=set)
    """Steps due whose at-start conditions do not hold in the belief: while any is,
    no step planned after it starts (the plan is broken there; the replan comes
    sooner)."""


class TemporalDispatch(smach.Container):
    """Runs the steps of a temporal plan as they become ready (see the module doc).

    Outcomes: ``succeeded`` when every step succeeded, else the first failing step's
    outcome (``aborted``, ``invalid``, ``preempted``).

    ``clock``: the time the dispatch follows (default: the wall clock). On a simulated
    clock (a simulated world's), plan seconds are its seconds, ``time_scale`` is only
    reported (the clock paces itself), and the dispatcher and the steps' threads take
    turns on it in simulated-time order.
    """

    #: The dispatcher's key in its clock's order: before the steps (keys 0, 1, ...).
    DISPATCHER_KEY = -1

    def __init__(
        self,
        steps: Sequence[PlanStep],
        states: Sequence[TimedStepState],
        labels: Sequence[str],
        model: ActionModel,
        belief: WorldState,
        *,
        time_scale: float = 0.0,
        on_failure: str = "finish",
        clock: Clock | None = None,
    ) -> None:
        if on_failure not in POLICIES:
            raise ValueError(f"on_failure must be one of {', '.join(POLICIES)}, got {on_failure!r}")
        if time_scale < 0:
            raise ValueError(f"time_scale must be 0 or more, got {time_scale!r}")
        input_keys = sorted({k for s in states for k in s.get_registered_input_keys()})
        output_keys = sorted({k for s in states for k in s.get_registered_output_keys()})
        super().__init__(list(STEP_OUTCOMES), input_keys, output_keys)
        self.steps = list(steps)
        self.labels = list(labels)
        self.belief = belief
        self.time_scale = time_scale
        self.on_failure = on_failure
        self.clock = WALL_CLOCK if clock is None else clock
        #: Clock seconds per plan second: 1 on a simulated clock, else ``time_scale``.
        self.clock_per_plan_s = 1.0 if self.clock.simulated else time_scale
        origin = min((s.start or 0.0 for s in self.steps), default=0.0)
        self._origin = origin
        self.planned_start = [(s.start or 0.0) - origin for s in self.steps]
        self.plan_zero: float | None = None
        """The clock time of plan time 0, when it is given (a resumed run continues the
        timeline of the run it resumes: :meth:`plan_zero_now` of that run); None: the
        plan's first step is due when the dispatch starts."""
        prints = footprints(self.steps, model)
        self.waits = precedence(self.steps, model, prints)
        self.end_waits = end_precedence(self.steps, model, prints)
        self._states: dict[str, TimedStepState] = {}
        self._effects_lock = threading.Lock()
        self._order = list(labels)
        for label, state in zip(labels, states, strict=True):
            self._adopt_child(label, state)
            state.effects_lock = self._effects_lock
            self._states[label] = state
        self._remappers: dict[str, smach.Remapper] = {}
        self._run_state: _Dispatch | None = None
        self._wake = self.clock.condition()

    def settled_facts(self) -> frozenset[Fact]:
        """The belief's facts with the at-start changes of the steps in progress undone.

        What a checkpoint keeps: were the process to stop now, those steps would be
        abandoned (a robot stopped mid-drive is back where it began, as after a
        preempt) and run again from their start after a resume; numbers they spent
        stay spent. The belief itself, mid-step, can be a state no plan starts from
        (the courier at no place while it drives).
        """
        with self._effects_lock:
            facts = set(self.belief.facts)
            for state in self._states.values():
                if state.in_flight is not None:
                    removed, added = state.in_flight
                    facts.difference_update(added)
                    facts.update(removed)
        return frozenset(facts)

    # -- Container interface -------------------------------------------------------------
    def get_children(self) -> dict[str, smach.State]:
        return dict(self._states)

    def get_initial_states(self) -> list[str]:
        return [self.labels[j] for j, waits in enumerate(self.waits) if not waits]

    def get_active_states(self) -> list[str]:
        run = self._run_state
        if run is None:
            return []
        with self._wake:
            return [self.labels[i] for i in run.running]

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        return [
            (f"{edge.point}+{edge.lag:g}", self.labels[edge.before], self.labels[edge.after])
            for waits in self.waits
            for edge in waits
        ]

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: smach.UserData | None = None
    ) -> None:
        if userdata is not None:
            self.userdata.update(userdata)

    def consistency_problems(self) -> list[str]:
        # Every child is a step whose own check covers its skill.
        return []

    def _compile(self) -> None:
        self._remappers = {
            label: self._remapper(label, state, None) for label, state in self._states.items()
        }

    def _terminal_states(self) -> list[str]:
        return list(self._order)

    @property
    def makespan_planned(self) -> float:
        """When the last step ends in the plan (plan seconds from the first start)."""
        return max(
            (
                start + (s.duration or 0.0)
                for start, s in zip(self.planned_start, self.steps, strict=True)
            ),
            default=0.0,
        )

    def timeline(self) -> list[dict[str, Any]]:
        """Planned and actual start and end of every step (the Gantt view's rows)."""
        rows = []
        for label, state in self._states.items():
            timing = state.timing
            rows.append(
                {
                    "label": label,
                    "action": str(state.ground.step),
                    "outcome": state.record.outcome,
                    "planned_start": timing.planned_start,
                    "planned_duration": timing.planned_duration,
                    "actual_start": timing.actual_start,
                    "actual_end": timing.actual_end,
                }
            )
        return rows

    # -- execution -------------------------------------------------------------------------
    def _run(self) -> str | None:
        clock = self.clock
        with clock.turn(clock.admit(self.DISPATCHER_KEY)):
            return self._run_dispatch()

    def plan_zero_now(self) -> float | None:
        """While the dispatch runs on a simulated clock: the clock time of plan time 0
        (what a checkpoint keeps so that a resumed run keeps the timeline)."""
        run = self._run_state
        if run is None or not self.clock.simulated:
            return None
        return run.t0 - self._origin * self.clock_per_plan_s

    def _run_dispatch(self) -> str | None:
        if self.plan_zero is None:
            t0 = self.clock.now()
        else:
            t0 = self.plan_zero + self._origin * self.clock_per_plan_s
        run = _Dispatch(t0=t0, waiting=list(range(len(self.steps))))

        def since_start(t0: float = time.monotonic()) -> float:
            return time.monotonic() - t0  # (wall seconds: the viewer's timeline)

        for index, state in enumerate(self._states.values()):
            state.clock = since_start
            state.time_scale = self.time_scale
            state.before_end = lambda i=index: self._await_end(run, i)
            state.on_begun = lambda i=index: self._begun(run, i)
            state.on_failed = lambda outcome, i=index: self._failed(run, i, outcome)
        self._run_state = run
        self.belief.add_listener(self._poke)
        try:
            self._loop(run)
        finally:
            self.belief.remove_listener(self._poke)
            self._run_state = None
        if run.errors:
            raise run.errors[0]
        if run.failure is not None:
            return run.failure
        if self._preempt_requested or run.waiting:
            return "preempted"
        return "succeeded"

    def _await_end(self, run: _Dispatch, i: int) -> None:
        """Hold step ``i``'s end until its end predecessors happened (or the run stops)."""
        with self._wake:
            try:
                while not (
                    run.failure is not None
                    or self._preempt_requested
                    or run.errors
                    or i in run.released
                ):
                    if all(
                        edge.before in (run.started if edge.point == "start" else run.ended)
                        for edge in self.end_waits[i]
                    ):
                        return
                    if i not in run.holding:
                        run.holding.add(i)
                        self._wake.notify_all()  # the loop looks whether all are held
                    self._wake.wait_until(None)
            finally:
                run.holding.discard(i)

    def _begun(self, run: _Dispatch, i: int) -> None:
        """Step ``i``'s start point happened (its skill began its action)."""
        with self._wake:
            run.started.setdefault(i, self.clock.now())
            self._wake.notify_all()

    def _poke(self) -> None:
        with self._wake:
            self._wake.notify_all()

    def _loop(self, run: _Dispatch) -> None:
        with self._wake:
            while True:
                stopping = run.failure is not None or self._preempt_requested or run.errors
                due: float | None = None
                if not stopping:
                    due = self._start_ready(run)
                if not run.running and (stopping or not run.waiting):
                    return
                if run.running and due is None and run.holding >= set(run.running):
                    run.released |= run.holding  # nothing else can happen: let go
                    self._wake.notify_all()
                if not run.running and due is None and run.waiting:
                    # Nothing runs and nothing is due: start the first waiting step
                    # whose predecessors happened, so that it reports why it cannot.
                    if not self._force_start(run):
                        run.failure = "aborted"
                        return
                    continue
                self._wake.wait_until(due)

    def _ready_at(self, run: _Dispatch, j: int) -> float | None:
        """Clock time when step ``j`` may start, None while a predecessor has not happened."""
        scale = self.clock_per_plan_s
        at = run.t0 + self.planned_start[j] * scale
        for edge in self.waits[j]:
            happened = (run.started if edge.point == "start" else run.ended).get(edge.before)
            if happened is None:
                return None
            at = max(at, happened + edge.lag * scale)
        return at

    def _start_ready(self, run: _Dispatch) -> float | None:
        """Start every step that is ready; return when the next one is due (or None)."""
        now = self.clock.now()
        due: float | None = None
        facts = self.belief.facts
        ready: list[int] = []
        for j in list(run.waiting):
            at = self._ready_at(run, j)
            if at is None:
                continue
            if at > now:
                due = at if due is None else min(due, at)
                continue
            state = self._states[self.labels[j]]
            if state.check_preconditions and not state.ground.applicable(facts):
                run.blocked.add(j)  # wait for the belief to change (or for _force_start)
                continue
            run.blocked.discard(j)
            ready.append(j)
        # A step that cannot start holds back the steps planned after it: when the
        # running steps end and it still cannot, the replan comes at once (another
        # robot's later steps are not played to the plan's end meanwhile).
        hold = min((self.planned_start[b] for b in run.blocked), default=None)
        for j in ready:
            if hold is None or self.planned_start[j] <= hold + 1e-9:
                self._launch(run, j)
        return due if hold is None else None

    def _force_start(self, run: _Dispatch) -> bool:
        for j in sorted(run.waiting, key=lambda j: j not in run.blocked):
            at = self._ready_at(run, j)
            if at is not None:
                self._launch(run, j)
                # Started by force: its start point is now (it will report why it
                # cannot run), and the steps planned with it may go ahead.
                run.started.setdefault(j, self.clock.now())
                return True
        return False

    def _launch(self, run: _Dispatch, j: int) -> None:
        run.waiting.remove(j)  # its start point is when its skill begins (_begun)
        label = self.labels[j]
        # Its place in the clock's order is taken now, before this thread can wait.
        ticket = self.clock.admit(j)
        thread = threading.Thread(
            target=self._run_child, args=(run, j, ticket), name=f"dispatch-{label}", daemon=True
        )
        run.running[j] = thread
        try:
            thread.start()
        except BaseException:
            self.clock.discard(ticket)
            raise

    def _run_child(self, run: _Dispatch, j: int, ticket: Ticket) -> None:
        with self.clock.turn(ticket):
            self._run_step(run, j)

    def _run_step(self, run: _Dispatch, j: int) -> None:
        label = self.labels[j]
        state = self._states[label]
        outcome = "aborted"
        try:
            outcome = self._step(
                label, state, self._remappers[label], threading.current_thread().name
            )
        except BaseException as exc:  # reported by _run in the caller's thread
            with self._wake:
                run.errors.append(exc)
        with self._wake:
            run.running.pop(j, None)
            run.ended[j] = self.clock.now()
            run.started.setdefault(j, run.ended[j])  # a step that ended before it began
            run.outcomes[j] = outcome
            if outcome != "succeeded":
                self._failed(run, j, outcome)
            self._wake.notify_all()

    def _failed(self, run: _Dispatch, j: int, outcome: str) -> None:
        """Step ``j`` failed with ``outcome``: the first failure stops new starts (and,
        with ``on_failure="preempt"``, preempts the other steps still running)."""
        with self._wake:
            if run.failure is None and not run.errors:
                run.failure = outcome
                if self.on_failure == "preempt":
                    for other in run.running:
                        if other != j:
                            self._states[self.labels[other]].request_preempt()
            self._wake.notify_all()

    def request_preempt(self) -> None:
        super().request_preempt()
        self._poke()


def compile_temporal(
    steps: Sequence[PlanStep],
    skills: SkillRegistry,
    model: ActionModel,
    belief: WorldState,
    *,
    first_index: int = 1,
    check_preconditions: bool = True,
    on_finished: Callable[[StepRecord], None] | None = None,
    variants: Mapping[int, str] | None = None,
    time_scale: float = 0.0,
    on_failure: str = "finish",
    world: World | None = None,
    clock: Clock | None = None,
) -> CompiledPlan:
    """A temporal plan as a :class:`TemporalDispatch` of :class:`TimedStepState` steps
    (labels as for sequential plans: ``03_NAVIGATE_R1_DOCK_HALL``). The dispatch follows
    ``clock``, by default the clock of ``world`` (the wall clock without one)."""
    steps = list(steps)
    width = max(2, len(str(first_index + len(steps))))
    labels = [step_label(first_index + i, s, width) for i, s in enumerate(steps)]
    states: list[TimedStepState] = []
    for i, step in enumerate(steps):
        skill_state, skill = skills.create(step, (variants or {}).get(i))
        state = TimedStepState(
            first_index + i,
            model.ground(step),
            belief,
            skill,
            check_preconditions=check_preconditions,
            on_finished=on_finished,
            world=world,
        )
        state.add("SKILL", skill_state)
        states.append(state)
    dispatch = TemporalDispatch(
        steps,
        states,
        labels,
        model,
        belief,
        time_scale=time_scale,
        on_failure=on_failure,
        clock=clock_of(world) if clock is None else clock,
    )
    return CompiledPlan(
        dispatch,
        steps,
        labels,
        list(states),
        [[i] for i in range(len(steps))],
        settled_facts=dispatch.settled_facts,
    )
