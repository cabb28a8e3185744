"""One step of a temporal plan: a :class:`TimedStepState`.

At-start conditions are checked and at-start effects (and numeric ones) reach the
belief when it starts; its over-all conditions are checked on every change of the
belief (a belief listener, no polling) and a violation preempts its skill: the step
ends ``aborted`` naming the condition. When the skill succeeds, the at-end conditions
are checked and the at-end effects applied, computed in the belief of that moment (a
battery drained meanwhile by another action is decreased from its current value).

Skills receive, besides the usual step keys, the planned duration in
``ud.duration`` (:data:`DURATION_KEY`, plan seconds), ``ud.end_ready``
(:data:`END_READY_KEY`: a callable that returns once the plan lets the step end) and
``ud.begun`` (:data:`BEGUN_KEY`: a callable a skill that declares it as an input key
calls once its action has begun).

The dispatcher that runs the step talks to it through one :class:`StepHooks` object
(its clock, its time scale, and the calls at the start point, before the end and on a
failure), bound for each run with :meth:`TimedStepState.bind`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import smach
from plan_bridge.execution.steps import StepRecord, StepState
from plan_bridge.execution.timeline import ActionEnded, ActionStarted, Timing
from plan_bridge.pddl.task import Fact
from plan_bridge.skills.registry import STEP_KEYS

__all__ = [
    "BEGUN_KEY",
    "DURATION_KEY",
    "END_READY_KEY",
    "TIMED_STEP_KEYS",
    "StepHooks",
    "TimedStepState",
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
#: The keys a timed step provides to its skill (they do not cross its boundary).
TIMED_STEP_KEYS = (*STEP_KEYS, DURATION_KEY, END_READY_KEY, BEGUN_KEY)


@dataclass(frozen=True)
class StepHooks:
    """What a timed step asks of the dispatcher that runs it (the defaults: a step run
    on its own, by the wall clock, with nothing to wait for)."""

    elapsed: Callable[[], float] = time.monotonic
    """The step's clock for its :class:`~plan_bridge.execution.timeline.Timing` (wall
    seconds since the dispatch began)."""
    time_scale: float = 0.0
    """The dispatch's wall seconds per plan second (told to the viewer's timeline)."""
    before_end: Callable[[], None] | None = None
    """Called when the skill succeeded, before the end point: the dispatcher holds the
    end until the points planned before it have happened."""
    on_begun: Callable[[], None] | None = None
    """Called once at the step's start point (see :data:`BEGUN_KEY`)."""
    on_failed: Callable[[str], None] | None = None
    """Called with the outcome when the step fails, before what it observed reaches the
    belief: no step is started on the strength of those observations after the failure
    that stops new starts."""


class TimedStepState(StepState):
    """A step of a temporal plan: at-start checks and effects when it starts, over-all
    conditions watched while its skill runs, at-end checks and effects on success. Made
    as a :class:`~plan_bridge.execution.steps.StepState` is; its ``hold`` is not used
    (the dispatcher holds a temporal plan, not its steps)."""

    provided_keys = TIMED_STEP_KEYS

    def _set_up(self) -> None:
        step = self.ground.step
        self.timing = Timing(step.start or 0.0, step.duration or 0.0)
        #: How the step reaches the dispatcher that runs it (:meth:`bind`); a step run
        #: on its own: the defaults.
        self.hooks = StepHooks()
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

    def bind(self, hooks: StepHooks) -> None:
        """Let the dispatcher about to run this step reach it through ``hooks``."""
        self.hooks = hooks

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
        data = self._give_step_keys()
        data[DURATION_KEY] = self.timing.planned_duration
        data[END_READY_KEY] = self._end_ready
        data[BEGUN_KEY] = self._begun
        self._has_begun = False
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
            self._end_ready()
        finally:
            self.belief.remove_listener(watch)
        outcome, observations = self._skill_result(record, skill_outcome, label)
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
            if self.hooks.on_failed is not None:
                self.hooks.on_failed(outcome)
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
        if self.hooks.before_end is not None and not self._violation:
            self.hooks.before_end()

    def _begun(self) -> None:
        with self._begun_once:
            if self._has_begun:
                return
            self._has_begun = True
        if self.hooks.on_begun is not None:
            self.hooks.on_begun()

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
        super()._started()
        timing = self.timing
        timing.actual_start = self.hooks.elapsed()
        timing.actual_end = None
        self._announce(
            ActionStarted,
            index=self.index,
            action=str(self.ground.step),
            planned_start=timing.planned_start,
            planned_duration=timing.planned_duration,
            actual_start=timing.actual_start,
            time_scale=self.hooks.time_scale,
        )

    def _ended(self, outcome: str) -> None:
        timing = self.timing
        timing.actual_end = self.hooks.elapsed()
        self._announce(
            ActionEnded,
            index=self.index,
            action=str(self.ground.step),
            outcome=outcome,
            planned_start=timing.planned_start,
            planned_duration=timing.planned_duration,
            actual_start=timing.actual_start or 0.0,
            actual_end=timing.actual_end,
        )
