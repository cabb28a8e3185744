"""The fakes users get in smach.testing."""

from __future__ import annotations

import threading

import pytest

import smach
from smach.testing import BlockingState, EventRecorder, RaisingState, ScriptedState


def test_scripted_state_returns_outcomes_in_order_then_repeats_the_last() -> None:
    state = ScriptedState(["a", "b"])
    ud = smach.UserData()
    assert [state.execute(ud) for _ in range(4)] == ["a", "b", "b", "b"]
    assert state.call_count == 4


def test_scripted_state_records_inputs_and_writes_outputs() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    sm.userdata.x = 5
    state = ScriptedState(["done"], input_keys=["x"], writes={"y": 6})
    with sm:
        smach.StateMachine.add("S", state)
    sm.execute()
    assert state.calls[0].inputs == {"x": 5}
    assert sm.userdata.y == 6


@pytest.mark.timeout(10)
def test_blocking_state_returns_preempted_or_the_released_outcome() -> None:
    state = BlockingState()
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(state.execute(smach.UserData())))
    runner.start()
    assert state.started.wait(5)
    state.release("done")
    runner.join(5)
    assert result == ["done"]
    state.request_preempt()
    assert state.execute(smach.UserData()) == "preempted"


def test_blocking_state_gives_up_after_its_timeout() -> None:
    assert BlockingState(timeout=0.01, timeout_outcome="done").execute(smach.UserData()) == "done"


def test_raising_state_raises_what_it_was_given() -> None:
    with pytest.raises(KeyError):
        RaisingState(KeyError("k")).execute(smach.UserData())


@pytest.mark.timeout(10)
def test_event_recorder_waits_for_a_matching_event() -> None:
    recorder = EventRecorder()
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("S", ScriptedState(["done"], delay=0.05))
    sm.add_listener(recorder)
    runner = threading.Thread(target=sm.execute)
    runner.start()
    event = recorder.wait_for(lambda e: e.kind == "container_terminated")
    runner.join(5)
    assert event.path == "/ROOT"
    with pytest.raises(TimeoutError):
        recorder.wait_for(lambda e: e.kind == "never", timeout=0.01)
