"""Nested StateMachines: a parent's loop runs a plain child machine's run itself.

Whatever the depth, the run takes the same Python stack (so it never crosses one of
CPython's frame-stack chunks per execution), and every protocol step of every level
happens as it would in a call: keys, log lines, callbacks, events, errors, preemption,
shutdown, running flags.
"""

from __future__ import annotations

import sys
import threading
from typing import Any

import pytest
from smach_helpers import HANG, Blocker, Fn, Leaf, LogRecorder, all_flags, join, preempt_when

import smach
from smach.events import ErrorRaised, Event
from smach.exceptions import InvalidStateError, InvalidTransitionError, InvalidUserCodeError


def _stack_depth() -> int:
    frame = sys._getframe(1)
    depth = 0
    while frame is not None:
        depth += 1
        frame = frame.f_back  # type: ignore[assignment]
    return depth


def _tower(leaf: smach.State, depth: int, keys: tuple[str, ...] = ()) -> list[smach.StateMachine]:
    """``depth`` machines, each holding the next, ``leaf`` at the bottom (its outcomes are
    every machine's); outermost first."""
    outcomes = leaf.get_registered_outcomes()
    inner = leaf
    levels = []
    for _ in range(depth):
        sm = smach.StateMachine(outcomes, input_keys=keys, output_keys=keys)
        with sm:
            smach.StateMachine.add("CHILD", inner, {o: o for o in outcomes})
        levels.append(sm)
        inner = sm
    return levels[::-1]


def _leaf_depth(depth: int) -> int:
    seen: list[int] = []

    def record(state: Fn, ud: Any) -> str:
        seen.append(_stack_depth())
        return "done"

    root = _tower(Fn(record, ["done", "preempted"]), depth)[0]
    assert root.execute() == "done"
    return seen[0]


def test_a_leaf_runs_at_the_same_stack_depth_under_one_machine_or_sixty() -> None:
    assert _leaf_depth(60) == _leaf_depth(2) == _leaf_depth(1)


def test_a_machine_that_replaces_run_children_is_called_at_each_level() -> None:
    runs: list[str] = []

    class Counting(smach.StateMachine):
        def run_children(self) -> str | None:
            runs.append(self.path)
            return super().run_children()

    inner = Counting(["done"])
    inner.add("LEAF", Leaf())
    outer = smach.StateMachine(["done"])
    outer.add("SUB", inner)
    assert not Counting._runs_inline
    assert outer.execute() == "done"
    assert runs == ["/ROOT/SUB"]


def test_a_key_goes_down_every_level_and_its_new_value_comes_back_up() -> None:
    def bump(state: Fn, ud: Any) -> str:
        ud.x = ud.x + 1
        return "done"

    root = _tower(Fn(bump, ["done", "preempted"], io_keys=["x"]), 20, ("x",))[0]
    ud = smach.UserData({"x": 41})
    assert root.execute(ud) == "done"
    assert root.execute(ud) == "done"
    assert ud.x == 43


def test_every_level_writes_its_starting_and_terminating_lines_in_call_order(
    logs: LogRecorder,
) -> None:
    levels = _tower(Leaf(["done", "preempted"]), 3)
    levels[0].set_root_path("/TOP")
    assert levels[0].execute() == "done"
    start = "State machine starting in initial state 'CHILD' with userdata: \n\t[]"
    end = "State machine terminating 'CHILD':'done':'done'"
    assert logs.info == [start, start, start, end, end, end]


def test_callbacks_of_an_inner_machine_see_each_of_its_runs() -> None:
    calls: list[tuple[str, Any]] = []
    levels = _tower(Leaf(["done", "preempted"]), 4)
    inner = levels[2]
    inner.register_start_cb(lambda ud, states: calls.append(("start", states)))
    inner.register_termination_cb(lambda ud, states, outcome: calls.append(("end", outcome)))
    assert levels[0].execute() == "done"
    assert levels[0].execute() == "done"
    assert calls == [("start", ["CHILD"]), ("end", "done")] * 2


def test_an_error_deep_down_reaches_the_root_naming_its_state_with_its_cause_and_one_event_per_level() -> (
    None
):
    events: list[Event] = []
    levels = _tower(Leaf(["done", "preempted"]), 4)
    root = levels[0]

    def fail(state: Fn, ud: Any) -> str:
        root.add_listener(events.append)  # (nobody watched the steps taken so far)
        raise ValueError("broken")

    with levels[-1]:
        smach.StateMachine.add("FAIL", Fn(fail, ["done"]))
    levels[-1].set_initial_state(["FAIL"])
    with pytest.raises(InvalidUserCodeError, match="/ROOT/CHILD/CHILD/CHILD/FAIL") as caught:
        root.execute()
    assert isinstance(caught.value.__cause__, ValueError)
    errors = [e.path for e in events if isinstance(e, ErrorRaised)]
    assert errors == ["/ROOT/CHILD/CHILD/CHILD", "/ROOT/CHILD/CHILD", "/ROOT/CHILD", "/ROOT"]
    assert not any(level.is_running() for level in levels)


def test_a_tree_that_failed_deep_down_runs_again() -> None:
    attempts: list[int] = []

    def fail_once(state: Fn, ud: Any) -> str:
        attempts.append(1)
        if len(attempts) == 1:
            raise RuntimeError("first time")
        return "done"

    levels = _tower(Fn(fail_once, ["done", "preempted"]), 5)
    with pytest.raises(InvalidUserCodeError, match="first time"):
        levels[0].execute()
    assert not any(level.is_running() for level in levels)
    assert levels[0].execute() == "done"


def test_an_inner_machine_made_inconsistent_stops_the_run_before_it_starts() -> None:
    levels = _tower(Leaf(["done", "preempted"]), 4)
    levels[2].set_initial_state(["MISSING"])
    with pytest.raises(InvalidTransitionError, match="initial state 'MISSING'"):
        levels[0].execute()
    assert not any(level.is_running() for level in levels)


def test_a_machine_running_in_another_thread_cannot_be_entered_again() -> None:
    blocker = Blocker()
    levels = _tower(blocker, 3)
    inner = levels[1]
    outcomes: list[str | None] = []
    thread = threading.Thread(target=lambda: outcomes.append(inner.execute()), daemon=True)
    thread.start()
    assert blocker.started.wait(HANG)
    with pytest.raises(InvalidStateError, match="already running"):
        levels[0].execute()
    inner.request_preempt()
    join(thread)
    assert outcomes == ["preempted"]


def test_a_preempt_of_the_root_reaches_a_leaf_ten_machines_down() -> None:
    blocker = Blocker()
    levels = _tower(blocker, 10)
    thread = preempt_when(blocker.started, levels[0])
    assert levels[0].execute() == "preempted"
    join(thread)
    assert blocker.saw_preempt
    assert not any(all_flags(levels[0]).values())


def test_shutdown_during_a_deep_run_ends_every_level_with_none() -> None:
    stop = threading.Event()

    def leaf(state: Fn, ud: Any) -> str:
        stop.set()
        return "done"

    smach.is_shutdown = stop.is_set
    afters: list[Leaf] = []
    inner: smach.State = Fn(leaf)
    levels = []
    for _ in range(6):  # each level: CHILD, then AFTER (never reached: shutdown came first)
        sm = smach.StateMachine(["done"])
        with sm:
            smach.StateMachine.add("CHILD", inner, {"done": "AFTER"})
            afters.append(Leaf())
            smach.StateMachine.add("AFTER", afters[-1], {"done": "done"})
        levels.append(sm)
        inner = sm
    assert levels[-1].execute() is None
    assert [after.calls for after in afters] == [0] * 6
    assert not any(level.is_running() for level in levels)
