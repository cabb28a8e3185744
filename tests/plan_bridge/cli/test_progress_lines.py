"""The lines `plan-bridge run` prints, from the events of a mission (no planner, no
world): temporal steps in planned order with their planned times, repairs shown only
when adopted, one line per failed step, and a summary of a few short lines."""

from __future__ import annotations

import io
from typing import Any

from plan_bridge.cli.progress import ProgressPrinter, summary_lines
from plan_bridge.cli.run import ProgressPrinter as ProgressPrinterOfRun
from plan_bridge.execution.events import ExecutiveDecision, PlanComputed, StepFinished
from plan_bridge.execution.policy import ExecutionReport
from plan_bridge.execution.temporal import ActionStarted
from smach.introspection.events import ContainerStarted, ContainerTerminated, Event

EXECUTIVE = "/ROOT"


def plan(reason: str, steps: int = 3, status: str = "solved", **extra: Any) -> PlanComputed:
    return PlanComputed(
        path=EXECUTIVE,
        time=0.0,
        thread="main",
        reason=reason,
        planner="fast-downward",
        status=status,
        steps=tuple(f"(step{i})" for i in range(steps)) if status == "solved" else (),
        planning_time_s=0.25,
        explanation="" if status == "solved" else "no plan exists",
        **extra,
    )


def decision(name: str, reason: str = "because", step: str = "") -> ExecutiveDecision:
    return ExecutiveDecision(
        path=EXECUTIVE, time=0.0, thread="main", decision=name, reason=reason, step=step
    )


def started(index: int, action: str, start: float, duration: float) -> ActionStarted:
    return ActionStarted(
        path=f"{EXECUTIVE}/PLAN/{index:02d}_X",
        time=0.0,
        thread="step",
        index=index,
        action=action,
        planned_start=start,
        planned_duration=duration,
        actual_start=0.0,
    )


def finished(index: int, action: str, outcome: str = "succeeded") -> StepFinished:
    return StepFinished(
        path=f"{EXECUTIVE}/PLAN/{index:02d}_X",
        time=0.0,
        thread="step",
        index=index,
        action=action,
        outcome=outcome,
        skill_outcome=outcome,
        duration_s=0.002,
    )


def printed(*events: Event, verbose: bool = False) -> list[str]:
    out = io.StringIO()
    printer = ProgressPrinter(out, verbose=verbose)
    for event in events:
        printer(event)
    return out.getvalue().splitlines()


def test_the_printer_is_still_importable_from_the_run_module() -> None:
    assert ProgressPrinterOfRun is ProgressPrinter


def plan_machine(kind: str = "TemporalDispatch", *, ended: bool = False) -> Event:
    """The plan's machine starting (or ending) its run."""
    path = f"{EXECUTIVE}/PLAN"
    if ended:
        return ContainerTerminated(
            path=path, time=0.0, thread="main", terminal_states=(), outcome="aborted"
        )
    return ContainerStarted(
        path=path, time=0.0, thread="main", container_type=kind, initial_states=()
    )


def test_a_temporal_step_shows_its_planned_start_and_duration_and_comes_in_planned_order() -> None:
    lines = printed(
        plan("initial plan", 3, makespan=9.0),
        plan_machine(),
        started(1, "(hold-door r1 d)", 0.0, 5.0),
        started(2, "(pass-door r2 d)", 1.0, 3.0),
        finished(2, "(pass-door r2 d)"),  # ends first: it is planned inside the hold
        started(3, "(grab r2 box)", 4.0, 2.0),
        finished(3, "(grab r2 box)"),
        finished(1, "(hold-door r1 d)"),
        plan_machine(ended=True),
    )
    assert lines == [
        "[plan] initial plan: 3 steps, makespan 9.00 s (fast-downward, 0.25 s)",
        "  step 1: (hold-door r1 d) planned at 0.00 s for 5.00 s -> succeeded [2 ms]",
        "  step 2: (pass-door r2 d) planned at 1.00 s for 3.00 s -> succeeded [2 ms]",
        "  step 3: (grab r2 box) planned at 4.00 s for 2.00 s -> succeeded [2 ms]",
    ]


def test_a_temporal_step_line_is_printed_once_the_steps_planned_before_it_ended() -> None:
    out = io.StringIO()
    printer = ProgressPrinter(out)
    for event in (plan("initial plan", 4, makespan=3.0), plan_machine()):
        printer(event)
    printer(started(2, "(b)", 1.0, 1.0))
    printer(finished(2, "(b)"))  # step 1 has not even started (it waits for the belief)
    assert len(out.getvalue().splitlines()) == 1
    printer(started(1, "(a)", 0.0, 2.0))
    printer(finished(1, "(a)", "aborted"))  # the failure stops new starts: 3 never runs
    printer(started(4, "(d)", 2.0, 1.0))
    printer(finished(4, "(d)"))
    assert out.getvalue().splitlines()[1:] == [
        "  step 1: (a) planned at 0.00 s for 2.00 s -> aborted [2 ms]",
        "  step 2: (b) planned at 1.00 s for 1.00 s -> succeeded [2 ms]",
    ]
    printer(plan_machine(ended=True))  # the plan's run is over: 4 is not held any longer
    assert out.getvalue().splitlines()[-1].startswith("  step 4: (d)")


def test_the_next_plan_of_a_temporal_mission_is_numbered_on() -> None:
    lines = printed(
        plan("initial plan", 1, makespan=1.0),
        plan_machine(),
        started(1, "(a)", 0.0, 1.0),
        finished(1, "(a)", "aborted"),
        plan_machine(ended=True),
        decision("replan", "(a) aborted"),
        plan("replan: (a) aborted", 2, makespan=2.0),
        plan_machine(),
        started(3, "(c)", 1.0, 1.0),
        started(2, "(b)", 0.0, 2.0),
        finished(3, "(c)"),
        finished(2, "(b)"),
    )
    assert [line.split(":")[0] for line in lines[-2:]] == ["  step 2", "  step 3"]


def test_the_steps_of_a_sequential_plan_are_printed_as_they_end() -> None:
    lines = printed(
        plan("initial plan", 2),
        plan_machine("StateMachine"),
        finished(2, "(b)"),
        finished(1, "(a)"),
    )
    assert lines[1:] == [
        "  step 2: (b) -> succeeded [2 ms]",
        "  step 1: (a) -> succeeded [2 ms]",
    ]


def test_a_sequential_step_line_is_as_before() -> None:
    assert printed(finished(4, "(move r1 a b)", "aborted")) == [
        "  step 4: (move r1 a b) -> aborted [2 ms]"
    ]


def test_a_rejected_repair_is_not_printed_as_a_new_plan() -> None:
    lines = printed(
        plan("initial plan", 6),
        finished(4, "(move r1 office hallway)", "aborted"),
        plan("repair: re-establish (at r1 office)", 4),
        decision("repair-rejected", "the repair needs 4 extra steps to rescue 3"),
        decision("replan", "(move r1 office hallway) aborted"),
        plan("replan: (move r1 office hallway) aborted", 5),
    )
    assert [line for line in lines if line.startswith("[plan]")] == [
        "[plan] initial plan: 6 steps (fast-downward, 0.25 s)",
        "[plan] new plan: 5 steps (fast-downward, 0.25 s)",
    ]
    assert not any("repair" in line for line in lines)


def test_a_failed_repair_is_not_printed_as_a_new_plan_either() -> None:
    lines = printed(
        plan("repair: re-establish (at r1 office)", status="unsolvable"),
        decision("replan", "(move r1 office hallway) aborted"),
        plan("replan: (move r1 office hallway) aborted", status="timeout"),
    )
    assert lines == [
        "[replan] (move r1 office hallway) aborted",
        "[plan] no new plan: timeout: no plan exists",
    ]


def test_an_adopted_repair_prints_its_decision_then_its_plan() -> None:
    lines = printed(
        plan("repair: re-establish (at r1 office)", 2),
        decision("repair", "(move r1 a b) aborted; 2 steps re-establish (at r1 office)"),
    )
    assert lines == [
        "[repair] (move r1 a b) aborted; 2 steps re-establish (at r1 office)",
        "[plan] repair: 2 steps (fast-downward, 0.25 s)",
    ]


def test_verbose_output_shows_a_rejected_repair_with_its_reason() -> None:
    lines = printed(
        plan("repair: re-establish (at r1 office)", 4),
        decision("repair-rejected", "a new plan fits better"),
        verbose=True,
    )
    assert lines == [
        "[plan] repair: re-establish (at r1 office): 4 steps (fast-downward, 0.25 s)",
        "[repair-rejected] a new plan fits better",
    ]


def test_every_aborted_step_gets_its_own_recovery_line() -> None:
    lines = printed(
        finished(3, "(pick r2 parcel1 b)", "aborted"),
        finished(2, "(move r1 a b)", "succeeded"),
        finished(5, "(pick r1 cup1 a)", "aborted"),
        finished(6, "(drop r1 cup1 c)", "invalid"),
        decision("retry", "(pick r2 parcel1 b) aborted; the plan is still valid"),
    )
    assert lines[-3:] == [
        "[retry] (pick r2 parcel1 b) aborted; the plan is still valid",
        "[recover] step 5 (pick r1 cup1 a) aborted too: it stays in the held plan and runs again",
        "[recover] step 6 (drop r1 cup1 c) invalid too: it stays in the held plan and runs again",
    ]


def test_the_steps_a_replan_is_about_are_told_with_its_result() -> None:
    failed = (finished(3, "(a)", "aborted"), finished(4, "(b)", "aborted"))
    replaced = printed(*failed, decision("replan", "(a) aborted"), plan("replan: (a) aborted"))
    assert replaced[-2:] == [
        "[plan] new plan: 3 steps (fast-downward, 0.25 s)",
        "[recover] step 4 (b) aborted too: the new plan, made from the belief, replaces it",
    ]
    held = printed(
        *failed,
        decision("replan", "(a) aborted"),
        plan("replan: (a) aborted", status="timeout"),
        decision("hold", "no plan (timeout); the held plan is still valid"),
    )
    assert held[-1] == "[recover] step 4 (b) aborted too: it stays in the held plan and runs again"
    ended = printed(
        *failed,
        decision("replan", "(a) aborted"),
        ContainerTerminated(path=EXECUTIVE, time=0.0, thread="main",
                            terminal_states=(), outcome="aborted"),
    )  # fmt: skip
    assert ended[-1] == "[recover] step 4 (b) aborted too: not run again: the mission ended"


def test_a_continue_keeps_the_other_failed_steps_in_the_rest_of_the_plan() -> None:
    lines = printed(
        finished(3, "(a)", "aborted"),
        finished(4, "(b)", "aborted"),
        decision("continue", "(a) aborted; the rest of the plan is still valid"),
    )
    assert lines[-1] == (
        "[recover] step 4 (b) aborted too: it stays in the rest of the plan and runs again"
    )


def test_the_summary_is_a_few_short_lines() -> None:
    report = ExecutionReport(
        outcome="succeeded",
        goal_reached=True,
        actions_executed=17,
        actions_failed=4,
        retries=2,
        replans=1,
        planner_calls=2,
        plans_reused=1,
        planning_time_s=0.11,
        execution_time_s=0.02,
        total_time_s=0.13,
    )
    assert summary_lines("succeeded", report, 13) == [
        "summary: succeeded (goal reached)",
        "  actions: 17 run, 4 failed; 13 faults injected",
        "  recovery: 2 retries, 1 replan",
        "  time: planning 0.11 s (2 planner calls, 1 plan reused), execution 0.02 s, total 0.13 s",
    ]


def test_the_summary_of_a_failed_mission_ends_with_the_reason() -> None:
    report = ExecutionReport(
        outcome="aborted",
        actions_executed=6,
        actions_failed=1,
        repair_attempts=1,
        planner_calls=2,
        explanation="(navigate pr2 a b) aborted; the policy allows no further recovery",
    )
    lines = summary_lines("aborted", report, None)
    assert lines[0] == "summary: aborted (goal NOT reached)"
    assert lines[1] == "  actions: 6 run, 1 failed"
    assert lines[2] == "  recovery: 0 repairs adopted (1 planned)"
    assert lines[-1] == (
        "  reason: (navigate pr2 a b) aborted; the policy allows no further recovery"
    )
    assert all(len(line) <= 100 for line in lines[:-1])
