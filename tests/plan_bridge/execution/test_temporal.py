"""Temporal plans dispatched as SMACH: start order, overlap, over-all monitoring, late actions."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import pytest

import smach
from plan_bridge.belief import Belief
from plan_bridge.execution.compile import compile_plan
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.steps import CompiledPlan, PlanHold, StepRecord
from plan_bridge.execution.temporal import (
    ActionEnded,
    ActionStarted,
    TemporalDispatch,
    compile_temporal,
    end_precedence,
    precedence,
)
from plan_bridge.pddl.task import PlanningTask, load_task, load_task_from_text
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import SkillRegistry

DATA = Path(__file__).resolve().parents[1] / "data" / "temporal"

pytestmark = pytest.mark.timeout(60)

PLAN = [
    PlanStep("hold-light", ("lamp", "yard"), 0.0, 4.0),
    PlanStep("undock", ("scout", "yard"), 0.0, 1.0),
    PlanStep("inspect", ("scout", "yard"), 1.01, 2.0),
]


@pytest.fixture(scope="module")
def task() -> PlanningTask:
    return load_task(DATA / "domain.pddl", DATA / "problem.pddl")


class Sleep(smach.State):
    """A skill that takes ``seconds`` (preemptable) and records what it was given."""

    def __init__(self, seconds: float = 0.0, seen: list[float] | None = None) -> None:
        super().__init__(["succeeded", "aborted", "preempted"], input_keys=["duration"])
        self.seconds = seconds
        self.seen = seen

    def execute(self, ud: smach.UserData) -> str:
        if self.seen is not None:
            self.seen.append(ud.duration)
        deadline = time.monotonic() + self.seconds
        while time.monotonic() < deadline:
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            time.sleep(0.002)
        return "succeeded"


def skills_with(**seconds: float) -> SkillRegistry:
    registry = SkillRegistry()
    registry.fallback = lambda step: Sleep(seconds.get(step.action.replace("-", "_"), 0.0))
    return registry


def run(
    task: PlanningTask, skills: SkillRegistry, steps: list[PlanStep], **options: object
) -> tuple[str | None, TemporalDispatch, Belief, list[object]]:
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    compiled = compile_plan(steps, skills, model, belief, **options)  # type: ignore[arg-type]
    dispatch = compiled.machine
    assert isinstance(dispatch, TemporalDispatch)
    events: list[object] = []
    dispatch._bus.add(events.append)
    return dispatch.execute(), dispatch, belief, events


def test_a_time_triggered_plan_compiles_to_one_dispatcher_whose_steps_overlap(
    task: PlanningTask,
) -> None:
    outcome, dispatch, belief, events = run(task, skills_with(hold_light=0.15), PLAN)
    assert outcome == "succeeded"
    assert ("inspected", "yard") in belief
    assert belief.values[("rounds",)] == 1.0 and belief.values[("energy", "scout")] == 7.0
    assert ("light-on", "yard") not in belief  # the at-end effect of hold-light
    rows = {row["action"]: row for row in dispatch.timeline()}
    light, inspect = rows["(hold-light lamp yard)"], rows["(inspect scout yard)"]
    # The inspection ran while the light was held: the two actions overlapped.
    assert inspect["actual_start"] < light["actual_end"]
    kinds = [type(e) for e in events if isinstance(e, ActionStarted | ActionEnded)]
    assert kinds.count(ActionStarted) == 3 and kinds.count(ActionEnded) == 3


def test_a_finished_plan_leaves_no_listener_on_the_belief_so_old_plans_can_be_freed(
    task: PlanningTask,
) -> None:
    # A mission of orders runs hundreds of plans against one belief: a listener left
    # behind would keep every old plan machine alive.
    outcome, _, belief, _ = run(task, skills_with(hold_light=0.02), PLAN)
    assert outcome == "succeeded" and belief._listeners == []


def test_a_step_waits_for_the_end_of_a_causal_predecessor_and_the_start_of_an_overlapping_one(
    task: PlanningTask,
) -> None:
    waits = precedence(PLAN, ActionModel(task))
    inspect = {(edge.before, edge.point) for edge in waits[2]}
    assert inspect == {(0, "start"), (1, "end")}
    assert waits[0] == [] and waits[1] == []


def test_a_late_action_delays_its_dependents_instead_of_breaking_them(
    task: PlanningTask,
) -> None:
    outcome, dispatch, _, _ = run(task, skills_with(undock=0.3, hold_light=0.5), PLAN)
    assert outcome == "succeeded"
    rows = {row["action"]: row for row in dispatch.timeline()}
    undock, inspect = rows["(undock scout yard)"], rows["(inspect scout yard)"]
    assert inspect["actual_start"] >= undock["actual_end"]


def test_skills_receive_the_planned_duration(task: PlanningTask) -> None:
    seen: list[float] = []
    registry = SkillRegistry()
    registry.fallback = lambda step: Sleep(0.0, seen)
    outcome, *_ = run(task, registry, PLAN)
    assert outcome == "succeeded"
    assert sorted(seen) == [1.0, 2.0, 4.0]


def test_an_over_all_condition_broken_mid_action_preempts_the_step(task: PlanningTask) -> None:
    registry = skills_with(hold_light=5.0, inspect=5.0)
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    compiled = compile_plan(PLAN, registry, model, belief, on_failure="preempt")
    dispatch = compiled.machine
    outcome: list[str | None] = []
    runner = threading.Thread(target=lambda: outcome.append(dispatch.execute()))
    runner.start()
    deadline = time.monotonic() + 10
    while compiled.step_states[2].timing.actual_start is None and time.monotonic() < deadline:
        time.sleep(0.005)
    # Somebody switched the light off while the scout inspects.
    belief.observe([(("light-on", "yard"), False)])
    runner.join(20)
    assert outcome == ["aborted"]
    record = compiled.step_states[2].record
    assert record.outcome == "aborted"
    assert record.unmet == ("over all: (light-on yard)",)
    assert ("inspected", "yard") not in belief
    # The preempt policy stopped the light holder too.
    assert compiled.step_states[0].record.skill_outcome == "preempted"


def test_the_finish_policy_lets_the_other_running_steps_complete(task: PlanningTask) -> None:
    steps = [PlanStep("inspect", ("scout", "yard"), 0.0, 2.0), PLAN[0]]
    outcome, dispatch, belief, _ = run(task, skills_with(hold_light=0.1), steps)
    # inspect cannot start (docked); hold-light ran to its end meanwhile.
    assert outcome == "invalid"
    rows = {row["action"]: row for row in dispatch.timeline()}
    assert rows["(hold-light lamp yard)"]["outcome"] == "succeeded"
    assert rows["(inspect scout yard)"]["outcome"] == "invalid"
    assert ("light-on", "yard") not in belief  # its at-end effect was applied


def test_a_step_that_cannot_start_holds_back_the_steps_planned_after_it(
    task: PlanningTask,
) -> None:
    # inspect cannot start (docked). hold-light, planned with it, goes ahead; the second
    # hold-light, planned after it, waits with it: the dispatch ends (and a replan can
    # come) when the first hold-light ends, not after the rest of the plan was played.
    steps = [
        PlanStep("inspect", ("scout", "yard"), 0.0, 2.0),
        PlanStep("hold-light", ("lamp", "yard"), 0.0, 4.0),
        PlanStep("hold-light", ("lamp", "yard"), 4.5, 4.0),
    ]
    outcome, dispatch, _, _ = run(task, skills_with(hold_light=0.05), steps)
    assert outcome == "invalid"
    rows = [(row["planned_start"], row["outcome"]) for row in dispatch.timeline()]
    assert sorted(rows, key=lambda r: r[0]) == [(0.0, "invalid"), (0.0, "succeeded"), (4.5, "")]


def test_a_held_end_is_let_go_when_the_step_it_waits_for_can_never_start(
    task: PlanningTask,
) -> None:
    # The light is held until the inspection ends, but the scout is docked: the
    # inspection cannot start, so the holder is let go instead of waiting forever.
    steps = [PLAN[0], PlanStep("inspect", ("scout", "yard"), 0.01, 2.0)]
    assert (1, "end") in {(e.before, e.point) for e in end_precedence(steps, ActionModel(task))[0]}
    outcome, dispatch, _, _ = run(task, skills_with(), steps)
    assert outcome == "invalid"
    rows = {row["action"]: row for row in dispatch.timeline()}
    assert rows["(hold-light lamp yard)"]["outcome"] == "succeeded"
    assert rows["(inspect scout yard)"]["outcome"] == "invalid"


def test_time_scale_plays_the_plan_timeline(task: PlanningTask) -> None:
    outcome, dispatch, _, _ = run(task, skills_with(), PLAN, time_scale=0.05)
    assert outcome == "succeeded"
    rows = {row["action"]: row for row in dispatch.timeline()}
    # inspect is planned at 1.01 s: with 0.05 wall s per plan s, not before ~0.05 s.
    assert rows["(inspect scout yard)"]["actual_start"] >= 1.01 * 0.05
    assert dispatch.makespan_planned == pytest.approx(4.0)


def test_the_timed_check_accepts_overlap_and_refuses_a_broken_invariant(
    task: PlanningTask,
) -> None:
    model = ActionModel(task)
    facts = Belief(task.initial_facts, model.initial_values()).facts
    assert model.check_plan(PLAN, facts).valid
    late_light = [PLAN[0], PLAN[1], PlanStep("inspect", ("scout", "yard"), 3.5, 2.0)]
    check = model.check_plan(late_light, facts)
    assert not check.valid and check.unmet == ("over all: (light-on yard)",)


COUNTING = """
(define (domain counting)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types bot)
  (:predicates (ready ?b - bot) (done ?b - bot))
  (:functions (count))
  (:durative-action tick
    :parameters (?b - bot)
    :duration (= ?duration 1)
    :condition (at start (ready ?b))
    :effect (and (at start (increase (count) 1)) (at end (done ?b))
                 (at end (increase (count) 1)))))
"""


def test_overlapping_steps_increasing_one_number_lose_no_increase() -> None:
    from plan_bridge.pddl.task import load_task_from_text

    bots = [f"b{i}" for i in range(24)]
    problem = (
        f"(define (problem many) (:domain counting) (:objects {' '.join(bots)} - bot)"
        f" (:init {' '.join(f'(ready {b})' for b in bots)} (= (count) 0))"
        f" (:goal (>= (count) {2 * len(bots)})))"
    )
    counting = load_task_from_text(COUNTING, problem)
    steps = [PlanStep("tick", (b,), 0.0, 1.0) for b in bots]
    outcome, _, belief, _ = run(counting, skills_with(), steps)
    assert outcome == "succeeded"
    # Every step adds 1 at its start and 1 at its end, all at once in 24 threads.
    assert belief.values[("count",)] == 2.0 * len(bots)


class SlowToBegin(smach.State):
    """A skill that takes its action up only after ``delay`` s, then tells (ud.begun)."""

    def __init__(self, delay: float, times: dict[str, float]) -> None:
        super().__init__(["succeeded", "aborted", "preempted"], input_keys=["begun"])
        self.delay = delay
        self.times = times

    def execute(self, ud: smach.UserData) -> str:
        time.sleep(self.delay)
        self.times["light begun"] = time.monotonic()
        ud.begun()
        return "succeeded"


class Stamp(smach.State):
    def __init__(self, times: dict[str, float], name: str) -> None:
        super().__init__(["succeeded", "aborted", "preempted"])
        self.times = times
        self.name = name

    def execute(self, ud: smach.UserData) -> str:
        self.times[self.name] = time.monotonic()
        return "succeeded"


def test_a_step_planned_during_another_waits_until_that_one_has_begun(
    task: PlanningTask,
) -> None:
    times: dict[str, float] = {}
    registry = SkillRegistry()
    registry.fallback = lambda step: (
        SlowToBegin(0.2, times) if step.action == "hold-light" else Stamp(times, step.action)
    )
    steps = [PLAN[0], PLAN[2]]  # the inspection is planned while the light is held
    assert (0, "start") in {(e.before, e.point) for e in precedence(steps, ActionModel(task))[1]}
    outcome, _, _, _ = run(task, registry, PLAN)
    assert outcome == "succeeded"
    # The inspection began only once the holder said its action had begun.
    assert times["inspect"] >= times["light begun"]


def test_what_a_checkpoint_keeps_of_the_belief_leaves_out_steps_in_progress(
    task: PlanningTask,
) -> None:
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    seen: list[tuple[frozenset[object], frozenset[object]]] = []
    compiled: list[CompiledPlan] = []

    def finished(record: StepRecord) -> None:
        if record.step.action == "undock":  # while the light is still being held
            seen.append((compiled[0].settled_facts(), frozenset(belief.facts)))

    compiled.append(
        compile_plan(PLAN[:2], skills_with(hold_light=0.3), model, belief, on_finished=finished)
    )
    assert compiled[0].machine.execute() == "succeeded"
    ((kept, live),) = seen
    light, docked = ("light-on", "yard"), ("docked", "scout")
    assert light in live and light not in kept  # hold-light's start is undone in the checkpoint
    assert docked not in live and docked not in kept  # undock ended: its effects are kept
    assert compiled[0].settled_facts() == frozenset(belief.facts)  # nothing in progress any more


PROBE_DOMAIN = """(define (domain probing)
  (:requirements :strips :typing :durative-actions)
  (:types bot)
  (:predicates (idle ?b - bot) (ready ?b - bot) (probed ?b - bot) (done ?b - bot))
  (:durative-action probe :parameters (?b - bot) :duration (= ?duration 1)
    :condition (at start (idle ?b)) :effect (at end (probed ?b)))
  (:durative-action follow :parameters (?b - bot) :duration (= ?duration 1)
    :condition (at start (ready ?b)) :effect (at end (done ?b))))"""
PROBE_PROBLEM = """(define (problem once) (:domain probing) (:objects r - bot)
  (:init (idle r)) (:goal (and (probed r) (done r))))"""


class FailsSeeing(smach.State):
    """Fails, reporting that ``(ready r)`` holds (which ``follow`` waits for)."""

    def __init__(self, *args: str) -> None:
        super().__init__(["succeeded", "aborted", "preempted"], output_keys=["observations"])

    def execute(self, ud: smach.UserData) -> str:
        ud.observations = [(("ready", "r"), True)]
        return "aborted"


def test_a_step_is_not_started_on_what_a_failed_step_observed() -> None:
    # follow waits for (ready r), which only probe's failure reveals; the failure stops
    # new starts before its observations reach the belief, every time.
    task = load_task_from_text(PROBE_DOMAIN, PROBE_PROBLEM)
    plan = [PlanStep("probe", ("r",), 0.0, 1.0), PlanStep("follow", ("r",), 0.5, 1.0)]
    started: list[float] = []
    skills = SkillRegistry()
    skills.add("probe", FailsSeeing)
    skills.add("follow", lambda *args: Sleep(0.0, seen=started))
    for _ in range(5):
        # A slow finish (a checkpoint, say) leaves the dispatcher time to act on the
        # observations before the failing step's thread has ended.
        outcome, _, belief, _ = run(task, skills, plan, on_finished=lambda r: time.sleep(0.05))
        assert outcome == "aborted"
        assert ("ready", "r") in belief.facts  # the observation was kept
    assert started == []  # but follow never started


COURIER = Path(__file__).resolve().parents[3] / "domains" / "timed_courier"


def test_a_held_door_planned_to_close_as_the_robot_arrives_waits_for_the_robot() -> None:
    # Kairos plans the hold and the pass it covers to end at the same instant (PDDL's
    # over-all conditions need not hold at the end point); letting go first would
    # make the pass fail every time on a simulated clock, where ties are by index.
    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    plan = [
        PlanStep("hold-door", ("helper", "hall", "lab"), 46.004, 5.0),
        PlanStep("pass-door", ("courier", "hall", "lab"), 48.004, 3.0),
    ]
    waits = end_precedence(plan, ActionModel(task))
    assert {(edge.before, edge.point) for edge in waits[0]} == {(1, "start"), (1, "end")}
    assert waits[1] == []  # the pass does not wait for the door to close


def test_a_given_plan_zero_puts_the_steps_on_the_timeline_of_an_earlier_run(
    task: PlanningTask,
) -> None:
    # A resumed run: plan time 0 was at clock time 3 in the killed run, so the step
    # planned at 1.01 starts at 4.01 on the clock, not at once; a dispatch without it
    # starts its first step at once. (What a checkpoint keeps: plan_zero_now.)
    from plan_bridge.execution.clock import SimClock
    from plan_bridge.execution.temporal import compile_temporal

    seen: dict[str, float] = {}
    for label, zero in (("given", 3.0), ("none", None)):
        clock = SimClock()
        registry = SkillRegistry()

        def note(ud: smach.UserData, label: str = label, clock: SimClock = clock) -> str:
            seen[label] = clock.now()
            return "succeeded"

        registry.fallback = lambda step, note=note: smach.CBState(note, outcomes=["succeeded"])
        model = ActionModel(task)
        belief = Belief(task.initial_facts, model.initial_values())
        belief.observe([(("docked", "scout"), False), (("light-on", "yard"), True)])
        compiled = compile_temporal([PLAN[2]], registry, model, belief, clock=clock)
        dispatch = compiled.machine
        assert isinstance(dispatch, TemporalDispatch)
        dispatch.plan_zero = zero
        assert dispatch.plan_zero_now() is None  # not running
        assert dispatch.execute() == "succeeded"
    assert seen["given"] == pytest.approx(4.01)
    assert seen["none"] == pytest.approx(0.0)


def test_a_held_plan_starts_no_step_and_lets_the_running_ones_finish(task: PlanningTask) -> None:
    hold = PlanHold()
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    skills = skills_with(hold_light=0.3, undock=0.3)
    compiled = compile_plan(PLAN, skills, model, belief, hold=hold)
    dispatch = compiled.machine
    outcome: list[str | None] = []
    runner = threading.Thread(target=lambda: outcome.append(dispatch.execute()))
    runner.start()
    deadline = time.monotonic() + 10
    while compiled.step_states[0].timing.actual_start is None and time.monotonic() < deadline:
        time.sleep(0.002)
    hold.request()  # (an order arrived while the light and the undock run)
    runner.join(20)
    assert outcome == ["preempted"]
    records = {s.ground.name: s.record.outcome for s in compiled.step_states}
    # Running when held: finished, not stopped; inspect (after the undock) never started.
    assert records == {"hold-light": "succeeded", "undock": "succeeded", "inspect": ""}


def test_a_plan_holds_when_the_clock_reaches_its_alarm(task: PlanningTask) -> None:
    from plan_bridge.execution.clock import SimClock

    clock = SimClock()
    hold = PlanHold()
    hold.alarm = lambda: 1.005  # after undock's end (1.0), before inspect's start (1.01)
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    registry = SkillRegistry()
    registry.fallback = lambda step: ClockSkill(clock, step.duration or 0.0)
    compiled = compile_temporal(PLAN, registry, model, belief, clock=clock, hold=hold)
    dispatch = compiled.machine
    assert dispatch.execute() == "preempted"
    records = {s.ground.name: s.record.outcome for s in compiled.step_states}
    assert records == {"hold-light": "succeeded", "undock": "succeeded", "inspect": ""}
    assert clock.now() == pytest.approx(4.0)  # the light's hold ran to its planned end


class ClockSkill(smach.State):
    """A skill that takes ``seconds`` of a simulated clock."""

    def __init__(self, clock: Any, seconds: float) -> None:
        super().__init__(["succeeded", "aborted", "preempted"])
        self.clock = clock
        self.seconds = seconds

    def execute(self, ud: smach.UserData) -> str:
        self.clock.sleep(self.seconds, self.preempt_requested)
        return "succeeded"
