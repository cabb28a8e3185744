"""Retry: bounded re-runs of one child, with preempt-aware backoff."""

from __future__ import annotations

import threading

import pytest

import smach
from smach.testing import BlockingState, ScriptedState


def test_retry_reruns_until_a_non_retry_outcome() -> None:
    child = ScriptedState(["aborted", "aborted", "succeeded"])
    retry = smach.Retry.wrap("PICK", child, attempts=5)
    assert retry.execute() == "succeeded"
    assert child.call_count == 3
    assert retry.attempts_used == 3


def test_retry_returns_the_last_outcome_when_attempts_run_out() -> None:
    child = ScriptedState(["aborted"], outcomes=["aborted", "succeeded"])
    retry = smach.Retry.wrap("PICK", child, attempts=2)
    assert retry.execute() == "aborted"
    assert child.call_count == 2


def test_retry_infers_outcomes_and_keys_from_the_child_through_remapping() -> None:
    child = ScriptedState(
        ["done"], outcomes=["done", "aborted"], input_keys=["target"], output_keys=["result"]
    )
    retry = smach.Retry.wrap("X", child, remapping={"target": "goal", "result": "out"})
    assert set(retry.get_registered_outcomes()) == {"done", "aborted", "preempted"}
    assert retry.get_registered_input_keys() == ("goal",)
    assert retry.get_registered_output_keys() == ("out",)


def test_retry_is_transparent_inside_a_state_machine() -> None:
    sm = smach.StateMachine(outcomes=["ok", "failed"])
    sm.userdata.goal = "cup"
    pick = ScriptedState(["aborted", "succeeded"], input_keys=["target"], writes={"held": "cup"})
    with sm:
        smach.StateMachine.add(
            "PICK",
            smach.Retry.wrap("TRY", pick, remapping={"target": "goal"}, attempts=3),
            transitions={"succeeded": "ok", "aborted": "failed", "preempted": "failed"},
        )
    assert sm.execute() == "ok"
    assert sm.userdata.held == "cup"
    assert pick.calls[0].inputs == {"target": "cup"}


@pytest.mark.timeout(10)
def test_preempt_during_backoff_returns_preempted_at_once() -> None:
    child = ScriptedState(["aborted"], outcomes=["aborted", "succeeded"])
    retry = smach.Retry.wrap("X", child, attempts=3, backoff=30.0)
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(retry.execute()))
    runner.start()
    while child.call_count == 0:
        runner.join(0.01)
    retry.request_preempt()
    runner.join(5)
    assert not runner.is_alive()
    assert result == ["preempted"]
    assert child.call_count == 1
    assert not retry.preempt_requested()


@pytest.mark.timeout(10)
def test_preempt_reaches_the_running_child() -> None:
    child = BlockingState()
    retry = smach.Retry.wrap("X", child, retry_outcomes=["done"])
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(retry.execute()))
    runner.start()
    assert child.started.wait(5)
    retry.request_preempt()
    runner.join(5)
    assert result == ["preempted"]


def test_backoff_grows_geometrically_and_is_capped() -> None:
    retry = smach.Retry(attempts=5, backoff=0.5, backoff_factor=2.0, max_backoff=1.5)
    assert [retry._delay(n) for n in (1, 2, 3, 4)] == [0.5, 1.0, 1.5, 1.5]


@pytest.mark.parametrize(
    "kwargs", [{"attempts": 0}, {"attempts": "3"}, {"backoff": -1.0}, {"backoff_factor": 0.5}]
)
def test_bad_retry_parameters_are_refused(kwargs: dict[str, object]) -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.Retry(**kwargs)  # type: ignore[arg-type]


def test_retry_outcome_the_child_does_not_have_is_refused_when_added() -> None:
    retry = smach.Retry(retry_outcomes=["missed"])
    with pytest.raises(smach.InvalidStateError, match=r"retry outcomes \['missed'\]"):
        retry.add("X", ScriptedState(["done"]))


def test_a_retry_holds_one_child() -> None:
    retry = smach.Retry.wrap("X", ScriptedState(["done"]), retry_outcomes=["done"])
    with pytest.raises(smach.InvalidStateError, match="holds one child"):
        retry.add("Y", ScriptedState(["done"]))
