"""Temporal plans as SMACH: one dispatcher container, actions started on events.

A time-triggered plan (each step with a planned ``start`` and ``duration``) compiles
into a :class:`TemporalDispatch`: a ``smach`` container whose children are
:class:`~plan_bridge.execution.timed_step.TimedStepState` steps, run concurrently in
their own threads, like a Concurrence whose children start at different times. The
mechanism is in four modules:

* :mod:`~plan_bridge.execution.temporal_network`: the simple temporal network over the
  steps' start and end points (which points a step's start and end wait for);
* :mod:`~plan_bridge.execution.timed_step`: one step (at-start, over-all and at-end
  conditions and effects, its skill's keys);
* this module: the dispatcher that runs the steps on the network;
* :mod:`~plan_bridge.execution.timeline`: the events every step emits, and the
  recorder of a run's makespans.

**When a step starts.** A step *depends* on an earlier one when one writes an atom (or
a number) the other reads or writes. A dependent step waits for the earlier step's
**end** when the plan starts it after that end, else for its **start** (the two
overlap in the plan); in both cases it also waits the planned lag between those
points, times ``time_scale`` (wall seconds per plan second). With ``time_scale > 0``
no step starts before its planned time on the wall clock either (``t0 + start x
time_scale``), so a simulated run plays the plan's timeline. A step whose
predecessors have happened starts only when its at-start conditions hold in the
belief; while other steps run it waits for them (the belief may still change), and
when nothing runs it starts anyway and reports ``invalid``. So a late action delays
its dependents instead of breaking them, and independent actions planned with it go
ahead; those planned after it wait with it (the plan is broken there: the replan
comes when the steps running end, instead of after another robot's steps were played
to the plan's end).

**Whose clock.** The dispatcher follows a :class:`~plan_bridge.execution.clock.Clock`:
the wall clock by default (a robot), or a simulated world's clock. On a simulated clock
plan seconds are the clock's seconds: no step starts before its planned time, lags
included (the clock's own ``time_scale`` paces it for a viewer, or it jumps), and the
dispatcher and every step's thread take turns on it (one runs at a time; the next is
the one due first in simulated time, ties broken by step index, the dispatcher
first). Ends that fall at the same simulated instant are thus met in one order, and a
seeded simulated run is a function of its seed.

**Start points.** A step's *start point*, which the steps planned to start during it
wait for, is its skill's call of ``ud.begun`` or, for a skill without it, the moment
its skill starts. (A door held open at the start of one step is open before the step
that passes through it begins, whichever thread runs first.)

**When a step ends.** A step's end waits for the points planned before it of the
steps it interferes with, and for the end of an interfering step nested in it that is
planned to end at the same instant: a door held for a robot passing through is not
released before the robot is through, however quick the holding skill. The wait
happens when the skill calls ``ud.end_ready()`` (a skill holding something calls it
before letting go) and in any case before the at-end effects reach the belief.

**Failure.** The first step that ends other than ``succeeded`` stops new starts. The
policy ``on_failure`` says what happens to the steps still running: ``"finish"``
(default: their effects are real, a robot in the middle of a move completes it, and
the belief stays consistent with what happened) or ``"preempt"``. The container then
ends with that step's outcome, and the executive above validates, repairs or replans
from the belief as for sequential plans.

The names of the four modules are importable from here as well.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Unpack

import smach
from plan_bridge.belief import Belief
from plan_bridge.execution.clock import WALL_CLOCK, Clock, Ticket, clock_of
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.steps import (
    STEP_OUTCOMES,
    CompiledPlan,
    PlanContainer,
    PlanHold,
    StepOptions,
    build_steps,
)
from plan_bridge.execution.temporal_network import (
    EPSILON,
    Edge,
    end_precedence,
    footprints,
    is_temporal,
    precedence,
)
from plan_bridge.execution.timed_step import (
    BEGUN_KEY,
    DURATION_KEY,
    END_READY_KEY,
    StepHooks,
    TimedStepState,
)
from plan_bridge.execution.timeline import ActionEnded, ActionStarted, TimelineRecorder
from plan_bridge.pddl.task import Fact
from plan_bridge.planning.types import PlanStep
from plan_bridge.skills.registry import SkillRegistry

__all__ = [
    "BEGUN_KEY",
    "DURATION_KEY",
    "END_READY_KEY",
    "EPSILON",
    "ActionEnded",
    "ActionStarted",
    "Edge",
    "StepHooks",
    "TemporalDispatch",
    "TimedStepState",
    "TimelineRecorder",
    "compile_temporal",
    "end_precedence",
    "is_temporal",
    "precedence",
]

POLICIES = ("finish", "preempt")


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


class TemporalDispatch(PlanContainer):
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
        belief: Belief,
        *,
        time_scale: float = 0.0,
        on_failure: str = "finish",
        clock: Clock = WALL_CLOCK,
        hold: PlanHold | None = None,
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
        self.clock = clock
        #: Stops new starts while the running steps finish (:class:`PlanHold`).
        self.hold = hold
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
            self.adopt_child(label, state)
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

    def consistency_problems(self) -> list[str]:
        # Every child is a step whose own check covers its skill.
        return []

    def compile_children(self) -> None:
        self._remappers = {
            label: self.child_remapper(label, state) for label, state in self._states.items()
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
    def run_children(self) -> str | None:
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
            state.bind(
                StepHooks(
                    elapsed=since_start,
                    time_scale=self.time_scale,
                    before_end=partial(self._await_end, run, index),
                    on_begun=partial(self._begun, run, index),
                    on_failed=partial(self._failed, run, index),
                )
            )
        self._run_state = run
        self.belief.add_listener(self._poke)
        if self.hold is not None:
            self.hold.watch(self._poke)
        try:
            self._loop(run)
        finally:
            if self.hold is not None:
                self.hold.unwatch(self._poke)
            self.belief.remove_listener(self._poke)
            self._run_state = None
        if run.errors:
            raise run.errors[0]
        if run.failure is not None:
            return run.failure
        if self.preempt_requested() or run.waiting:
            return "preempted"
        return "succeeded"

    def _await_end(self, run: _Dispatch, i: int) -> None:
        """Hold step ``i``'s end until its end predecessors happened (or the run stops)."""
        with self._wake:
            try:
                while not (
                    run.failure is not None
                    or self.preempt_requested()
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
        hold = self.hold
        with self._wake:
            while True:
                stopping = (
                    run.failure is not None
                    or self.preempt_requested()
                    or bool(run.errors)
                    or (hold is not None and hold.held(self.clock.now()))
                )
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
                alarm = None if stopping or hold is None else hold.due()
                if alarm is not None:  # an order due: the dispatcher looks then
                    due = alarm if due is None else min(alarm, due)
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
            outcome = self.step_child(
                label, state, self._remappers[label], threading.current_thread().name
            )
        except BaseException as exc:  # reported by run_children in the caller's thread
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
    belief: Belief,
    *,
    time_scale: float = 0.0,
    on_failure: str = "finish",
    clock: Clock | None = None,
    **options: Unpack[StepOptions],
) -> CompiledPlan:
    """A temporal plan as a :class:`TemporalDispatch` of :class:`TimedStepState` steps
    (labels as for sequential plans: ``03_NAVIGATE_R1_DOCK_HALL``; ``options`` as for
    :func:`~plan_bridge.execution.compile.compile_plan`). The dispatch follows
    ``clock``, by default the clock of the ``world`` option (the wall clock without one)."""
    steps = list(steps)
    labels, states = build_steps(TimedStepState, steps, skills, model, belief, options)
    dispatch = TemporalDispatch(
        steps,
        states,
        labels,
        model,
        belief,
        time_scale=time_scale,
        on_failure=on_failure,
        clock=clock_of(options.get("world")) if clock is None else clock,
        hold=options.get("hold"),
    )
    return CompiledPlan(
        dispatch,
        steps,
        labels,
        list(states),
        [[i] for i in range(len(steps))],
        settled_facts=dispatch.settled_facts,
    )
