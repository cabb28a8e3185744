"""Bad input and misbehaving user code: clear errors, raised in the caller, never a hang."""

from __future__ import annotations

import threading

import pytest
from smach_helpers import HANG, Blocker, Fn, Leaf, LogRecorder

import smach


class Thing:
    def __init__(self) -> None:
        self.field = 1


# -- outcomes and transitions --------------------------------------------------------------------


def test_statemachine_child_returning_unregistered_outcome_raises_transition_error() -> None:
    # The original raises InvalidTransitionError (state_machine.py:277-284).
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["done"], result="surprise"))
    with pytest.raises(smach.InvalidTransitionError) as info:
        sm.execute()
    assert "surprise" in str(info.value)
    assert "/ROOT/A" in str(info.value)
    assert not sm.is_running()


@pytest.mark.parametrize("bad", [None, 42, ["done"]])
def test_statemachine_child_returning_non_string_raises_smach_error(bad: object) -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Fn(lambda s, ud: bad))
    with pytest.raises(smach.SmachError) as info:
        sm.execute()
    assert "/ROOT/A" in str(info.value)
    assert not sm.is_running()


def test_transition_to_unknown_label_fails_at_close_with_path() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidTransitionError) as info, sm:
        smach.StateMachine.add("A", Leaf(["ok"]), {"ok": "NOWHERE"})
    assert "NOWHERE" in str(info.value)
    assert "/ROOT/A" in str(info.value)


def test_transition_to_unknown_label_fails_at_execute_when_built_without_with() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["ok"]), {"ok": "NOWHERE"})
    with pytest.raises(smach.InvalidTransitionError) as info:
        sm.execute()
    assert "NOWHERE" in str(info.value)


def test_transition_on_unregistered_outcome_is_rejected_by_add() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidTransitionError) as info:
        sm.add("A", Leaf(["done"]), {"not_an_outcome": "done"})
    assert "not_an_outcome" in str(info.value)
    assert sm.get_children() == {}


def test_fall_through_outcome_that_is_not_a_container_outcome_is_reported() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["done", "orphan"]))
    with pytest.raises(smach.InvalidTransitionError) as info:
        sm.check_consistency()
    assert "orphan" in str(info.value)


def test_consistency_error_lists_every_problem_with_state_paths() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidTransitionError) as info, sm:
        smach.StateMachine.add("A", Leaf(["ok", "bad"]), {"ok": "GHOST1", "bad": "B"})
        smach.StateMachine.add("B", Leaf(["ok", "fail"]), {"ok": "GHOST2"})
        smach.StateMachine.add("C", Leaf(["unmapped"]))
    message = str(info.value)
    for expected in ("/ROOT/A", "GHOST1", "/ROOT/B", "GHOST2", "fail", "/ROOT/C", "unmapped"):
        assert expected in message
    assert len(sm.consistency_problems()) == 4


def test_nested_consistency_problem_names_nested_path() -> None:
    sub = smach.StateMachine(["done"])
    sub.add("X", Leaf(["lost"]))
    sm = smach.StateMachine(["done"])
    sm.add("SUB", sub)
    with pytest.raises(smach.SmachError) as info:
        sm.execute()
    assert "/ROOT/SUB/X" in str(info.value)
    assert "lost" in str(info.value)


def test_check_consistency_raises_invalid_transition_error() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidTransitionError):
        sm.check_consistency()


# -- empty containers, duplicates, bare strings ------------------------------------------------------


@pytest.mark.parametrize(
    "make",
    [
        lambda: smach.StateMachine(["done"]),
        lambda: smach.Sequence(["done"], "done"),
        lambda: smach.Concurrence(["done"], "done"),
        lambda: smach.Iterator(["done"], [], [], exhausted_outcome="done"),
    ],
    ids=["StateMachine", "Sequence", "Concurrence", "Iterator"],
)
def test_empty_container_raises_at_close_and_at_execute(make) -> None:  # type: ignore[no-untyped-def]
    container = make()
    with pytest.raises(smach.InvalidTransitionError), container:
        pass
    with pytest.raises(smach.SmachError):
        container.execute()


def test_duplicate_label_in_statemachine_is_rejected() -> None:
    sm = smach.StateMachine(["done"])
    first = Leaf()
    sm.add("A", first)
    with pytest.raises(smach.InvalidStateError) as info:
        sm.add("A", Leaf())
    assert "A" in str(info.value)
    assert sm["A"] is first


def test_duplicate_label_in_concurrence_is_rejected() -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("A", Leaf())
    with pytest.raises(smach.InvalidStateError):
        cc.add("A", Leaf())
    assert len(cc.get_children()) == 1


@pytest.mark.parametrize(
    "make",
    [
        lambda: smach.State(outcomes="done"),
        lambda: smach.State(outcomes=["done"], input_keys="abc"),
        lambda: smach.State(outcomes=["done"], output_keys="abc"),
        lambda: smach.State(outcomes=["done"], io_keys="abc"),
        lambda: smach.StateMachine(outcomes="done"),
        lambda: smach.Concurrence("done", "done"),
        lambda: smach.CBState(lambda ud: "done", outcomes="done"),
        lambda: smach.cb_interface(outcomes="done")(lambda ud: "done"),
        lambda: smach.State().register_outcomes("ab"),
    ],
)
def test_bare_string_where_a_list_is_expected_is_rejected(make) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(smach.InvalidStateError) as info:
        make()
    assert "string" in str(info.value)


def test_non_string_outcome_is_rejected() -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.State(outcomes=["done", 3])  # type: ignore[list-item]


# -- userdata keys ------------------------------------------------------------------------------------


def test_undeclared_key_read_raises_naming_state_and_declared_keys() -> None:
    sm = smach.StateMachine(["done"])
    sm.userdata.secret = 1
    sm.add("READER", Fn(lambda s, ud: ud.secret, input_keys=["allowed"]))
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    message = str(info.value)
    assert "/ROOT/READER" in message
    assert "secret" in message
    assert "allowed" in message


def test_undeclared_key_write_raises_naming_state_key_and_declared_keys() -> None:
    sm = smach.StateMachine(["done"])

    def body(s: Fn, ud: object) -> str:
        ud.undeclared = 1  # type: ignore[attr-defined]
        return "done"

    sm.add("WRITER", Fn(body, output_keys=["declared"]))
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    message = str(info.value)
    assert "/ROOT/WRITER" in message
    assert "undeclared" in message
    assert "declared" in message
    assert "undeclared" not in sm.userdata


def test_input_only_key_cannot_be_written() -> None:
    sm = smach.StateMachine(["done"])
    sm.userdata.x = 1

    def body(s: Fn, ud: object) -> str:
        ud.x = 2  # type: ignore[attr-defined]
        return "done"

    sm.add("S", Fn(body, input_keys=["x"]))
    with pytest.raises(smach.InvalidUserCodeError):
        sm.execute()
    assert sm.userdata.x == 1


def test_input_only_key_attribute_write_through_const_raises() -> None:
    thing = Thing()
    sm = smach.StateMachine(["done"])
    sm.userdata.thing = thing

    def body(s: Fn, ud: object) -> str:
        ud.thing.field = 99  # type: ignore[attr-defined]
        return "done"

    sm.add("S", Fn(body, input_keys=["thing"]))
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    assert "field" in str(info.value)
    assert thing.field == 1


def test_io_key_attribute_write_is_allowed() -> None:
    thing = Thing()
    sm = smach.StateMachine(["done"])
    sm.userdata.thing = thing

    def body(s: Fn, ud: object) -> str:
        ud.thing.field = 99  # type: ignore[attr-defined]
        return "done"

    sm.add("S", Fn(body, io_keys=["thing"]))
    assert sm.execute() == "done"
    assert thing.field == 99


def test_declared_but_missing_key_error_lists_available_keys() -> None:
    sm = smach.StateMachine(["done"])
    sm.userdata.available_one = 1
    sm.add("S", Fn(lambda s, ud: ud.wanted, input_keys=["wanted"]))
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    assert "wanted" in str(info.value)
    assert "available_one" in str(info.value)


# -- user code raising ------------------------------------------------------------------------------


def test_statemachine_child_exception_is_wrapped_with_path_and_cause() -> None:
    def body(s: Fn, ud: object) -> str:
        raise ZeroDivisionError("division by zero in user code")

    sm = smach.StateMachine(["done"])
    sm.add("CALC", Fn(body))
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    assert "/ROOT/CALC" in str(info.value)
    assert "ZeroDivisionError" in str(info.value)
    assert isinstance(info.value.__cause__, ZeroDivisionError)
    assert not sm.is_running()
    assert sm.get_active_states() == []


def test_nested_child_exception_surfaces_once_with_full_path() -> None:
    def body(s: Fn, ud: object) -> str:
        raise ValueError("deep")

    sub = smach.StateMachine(["done"])
    sub.add("LEAF", Fn(body))
    sm = smach.StateMachine(["done"])
    sm.add("SUB", sub)
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    assert "/ROOT/SUB/LEAF" in str(info.value)
    assert str(info.value).count("deep") == 1


@pytest.mark.timeout(10)
def test_concurrence_child_raising_raises_in_caller_and_stops_siblings() -> None:
    blocker = Blocker()

    def body(s: Fn, ud: object) -> str:
        blocker.started.wait(HANG)
        raise RuntimeError("child failed")

    cc = smach.Concurrence(["done"], "done")
    cc.add("BAD", Fn(body))
    cc.add("SIBLING", blocker)
    with pytest.raises(smach.InvalidUserCodeError) as info:
        cc.execute()
    assert "child failed" in str(info.value)
    assert "/ROOT/BAD" in str(info.value)
    assert blocker.saw_preempt
    assert not cc.is_running()


@pytest.mark.timeout(10)
@pytest.mark.parametrize("bad", [None, "unregistered", 7])
def test_concurrence_child_returning_bad_outcome_raises_in_caller(bad: object) -> None:
    blocker = Blocker()

    def body(s: Fn, ud: object) -> object:
        blocker.started.wait(HANG)
        return bad

    cc = smach.Concurrence(["done"], "done")
    cc.add("BAD", Fn(body))
    cc.add("SIBLING", blocker)
    with pytest.raises(smach.InvalidUserCodeError) as info:
        cc.execute()
    assert "/ROOT/BAD" in str(info.value)
    assert blocker.saw_preempt


@pytest.mark.timeout(10)
def test_concurrence_child_returning_none_raises_in_caller() -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("NONE", Fn(lambda s, ud: None))
    with pytest.raises(smach.InvalidUserCodeError):
        cc.execute()


@pytest.mark.timeout(10)
def test_concurrence_error_inside_statemachine_reaches_top_caller() -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("NONE", Fn(lambda s, ud: None))
    sm = smach.StateMachine(["done"])
    sm.add("CC", cc)
    with pytest.raises(smach.InvalidUserCodeError) as info:
        sm.execute()
    assert "/ROOT/CC/NONE" in str(info.value)


@pytest.mark.timeout(10)
def test_concurrence_outcome_cb_raising_raises_in_caller() -> None:
    def outcome_cb(outcomes: dict[str, str | None]) -> str:
        raise KeyError("oops")

    cc = smach.Concurrence(["done"], "done", outcome_cb=outcome_cb)
    cc.add("A", Leaf())
    with pytest.raises(smach.InvalidUserCodeError) as info:
        cc.execute()
    assert "outcome_cb" in str(info.value)


@pytest.mark.timeout(10)
@pytest.mark.parametrize("bad", ["unregistered", 5, ["done"]])
def test_concurrence_outcome_cb_returning_unregistered_outcome_raises(bad: object) -> None:
    cc = smach.Concurrence(["done"], "done", outcome_cb=lambda outcomes: bad)
    cc.add("A", Leaf())
    with pytest.raises(smach.InvalidUserCodeError) as info:
        cc.execute()
    assert repr(bad) in str(info.value)


@pytest.mark.timeout(10)
def test_concurrence_child_termination_cb_raising_raises_in_caller_without_hang() -> None:
    blocker = Blocker()

    def cb(outcomes: dict[str, str | None]) -> bool:
        raise RuntimeError("termination cb bug")

    cc = smach.Concurrence(["done"], "done", child_termination_cb=cb)
    cc.add("FAST", Leaf())
    cc.add("SLOW", blocker)
    with pytest.raises(smach.InvalidUserCodeError) as info:
        cc.execute()
    assert "termination cb bug" in str(info.value)
    assert blocker.saw_preempt


@pytest.mark.timeout(10)
@pytest.mark.parametrize("answer", ["FAST", ["GHOST"], 3])
def test_child_termination_cb_bad_answer_raises(answer: object) -> None:
    blocker = Blocker()
    cc = smach.Concurrence(["done"], "done", child_termination_cb=lambda outcomes: answer)
    cc.add("FAST", Leaf())
    cc.add("SLOW", blocker)
    with pytest.raises(smach.InvalidUserCodeError):
        cc.execute()


@pytest.mark.timeout(10)
def test_concurrence_transition_cb_raising_in_child_thread_does_not_hang(
    logs: LogRecorder,
) -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("A", Leaf())
    cc.add("B", Leaf())
    calls: list[int] = []
    lock = threading.Lock()

    def bad(ud: object, active: list[str]) -> None:
        with lock:
            calls.append(1)
        raise RuntimeError("transition cb bug")

    cc.register_transition_cb(bad)
    # Either outcome is acceptable as long as the caller gets control back.
    try:
        cc.execute()
    except smach.InvalidUserCodeError as exc:
        assert "transition cb bug" in str(exc)
    assert calls
    assert not cc.is_running()


def test_transition_callback_raising_is_logged_and_execution_continues(
    logs: LogRecorder,
) -> None:
    # The original wraps callback calls in try/except and logs "Could not execute
    # transition callback"; the spec does not change this.
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["next"]), {"next": "B"})
    last = Leaf()
    sm.add("B", last)

    def bad(ud: object, active: list[str]) -> None:
        raise RuntimeError("callback bug")

    sm.register_transition_cb(bad)
    assert sm.execute() == "done"
    assert last.calls == 1
    assert any("callback bug" in m or "transition" in m for m in logs.error)


def test_iterator_child_returning_unregistered_outcome_raises() -> None:
    it = smach.Iterator(["done"], [], [], it=[1], exhausted_outcome="done")
    it.set_contained_state("S", Leaf(["continue"], result="weird"), loop_outcomes=["continue"])
    with pytest.raises(smach.SmachError) as info:
        it.execute()
    assert "weird" in str(info.value)


def test_iterator_break_outcome_without_container_outcome_is_reported() -> None:
    it = smach.Iterator(["done"], [], [], it=[1], exhausted_outcome="done")
    with pytest.raises(smach.InvalidTransitionError) as info, it:
        smach.Iterator.set_contained_state(
            "S", Leaf(["continue", "found"]), loop_outcomes=["continue"]
        )
    assert "found" in str(info.value)


def test_error_message_of_missing_key_is_not_a_repr_of_the_message() -> None:
    ud = smach.UserData()
    with pytest.raises(KeyError) as info:
        ud["nope"]
    assert not str(info.value).startswith('"')


def test_nested_inconsistency_is_reported_before_anything_runs() -> None:
    from smach.testing import ScriptedState

    first = ScriptedState(["ok"])
    sub = smach.StateMachine(["done"])
    sub.add("A", ScriptedState(["x"]), transitions={"x": "NOWHERE"})
    root = smach.StateMachine(["done"])
    root.add("FIRST", first, transitions={"ok": "SUB"})
    root.add("SUB", sub)
    with pytest.raises(
        smach.InvalidTransitionError,
        match=r"/ROOT/SUB/A: outcome 'x' leads to unknown target 'NOWHERE'",
    ):
        root.execute()
    assert first.call_count == 0
    assert root.subtree_problems() and root.consistency_problems() == []


def test_terminating_log_line_names_the_last_state_its_outcome_and_the_container_outcome() -> None:
    from smach.testing import ScriptedState

    lines: list[str] = []
    smach.set_loggers(lines.append, lines.append, lines.append, lines.append)
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("PLACE", ScriptedState(["placed"]), transitions={"placed": "done"})
    sm.execute()
    assert "State machine terminating 'PLACE':'placed':'done'" in lines


def test_missing_remapped_key_error_names_both_keys() -> None:
    ud = smach.UserData()
    r = smach.Remapper(ud, ["goal"], [], {"goal": "target"})
    with pytest.raises(KeyError) as info:
        r.goal  # noqa: B018
    assert info.value.key == "goal"  # type: ignore[attr-defined]
    assert "userdata key 'goal' (remapped to 'target') is not available" in str(info.value)
