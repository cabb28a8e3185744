"""Timeout: preempt a child at a deadline and return a declared outcome."""

from __future__ import annotations

import threading

import pytest

import smach
from smach.testing import BlockingState, ScriptedState


@pytest.mark.timeout(10)
def test_child_running_past_the_deadline_is_preempted_and_timeout_is_returned() -> None:
    child = BlockingState(timeout=30)
    guard = smach.Timeout.wrap("WAIT", child, timeout=0.05)
    assert guard.execute() == "timeout"
    assert guard.timed_out
    assert not child.preempt_requested()


def test_child_finishing_in_time_passes_its_outcome_through() -> None:
    guard = smach.Timeout.wrap("QUICK", ScriptedState(["done"]), timeout=10)
    assert guard.execute() == "done"
    assert not guard.timed_out


def test_timeout_outcomes_include_the_childs_and_the_timeout_outcome() -> None:
    guard = smach.Timeout.wrap("X", ScriptedState(["done"]), timeout=1, timeout_outcome="late")
    assert set(guard.get_registered_outcomes()) == {"done", "preempted", "late"}


@pytest.mark.timeout(10)
def test_parent_preempt_is_passed_on_and_not_reported_as_timeout() -> None:
    child = BlockingState(timeout=30)
    guard = smach.Timeout.wrap("WAIT", child, timeout=20)
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(guard.execute()))
    runner.start()
    assert child.started.wait(5)
    guard.request_preempt()
    runner.join(5)
    assert result == ["preempted"]
    assert not guard.timed_out


@pytest.mark.timeout(10)
def test_timeout_inside_a_state_machine_leads_to_its_transition() -> None:
    sm = smach.StateMachine(outcomes=["gave_up", "ok"])
    with sm:
        smach.StateMachine.add(
            "WAIT",
            smach.Timeout.wrap("DOOR", BlockingState(timeout=30), timeout=0.02),
            transitions={"timeout": "gave_up", "done": "ok", "preempted": "gave_up"},
        )
    assert sm.execute() == "gave_up"


@pytest.mark.parametrize("bad", [0, -1.0, "5"])
def test_non_positive_timeout_is_refused(bad: object) -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.Timeout(bad)  # type: ignore[arg-type]
