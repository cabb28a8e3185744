"""smach.Iterator: loop a contained state over items."""

from __future__ import annotations

import pytest
from smach_helpers import Fn, Leaf

import smach


def collector(seen: list[object], outcome: str = "continue", **kw) -> Fn:  # type: ignore[no-untyped-def]
    def body(s: Fn, ud: object) -> str:
        seen.append(ud.it_data)  # type: ignore[attr-defined]
        return outcome

    return Fn(body, kw.pop("outcomes", ["continue", "stop"]), input_keys=["it_data"], **kw)


def make_iterator(items, state, **kwargs) -> smach.Iterator:  # type: ignore[no-untyped-def]
    it = smach.Iterator(["done", "stop"], [], [], it=items, exhausted_outcome="done")
    with it:
        smach.Iterator.set_contained_state("BODY", state, **kwargs)
    return it


def test_iterates_every_item_then_returns_exhausted_outcome() -> None:
    seen: list[object] = []
    it = make_iterator([1, 2, 3], collector(seen), loop_outcomes=["continue"])
    assert it.execute() == "done"
    assert seen == [1, 2, 3]


def test_empty_iterable_returns_exhausted_outcome_without_running_state() -> None:
    body = Leaf(["continue"])
    it = make_iterator([], body, loop_outcomes=["continue"])
    assert it.execute() == "done"
    assert body.calls == 0


def test_break_outcome_stops_the_loop() -> None:
    seen: list[object] = []

    def body(s: Fn, ud: object) -> str:
        seen.append(ud.it_data)  # type: ignore[attr-defined]
        return "stop" if ud.it_data == 2 else "continue"  # type: ignore[attr-defined]

    it = make_iterator(
        [1, 2, 3], Fn(body, ["continue", "stop"], input_keys=["it_data"]), break_outcomes=["stop"]
    )
    assert it.execute() == "stop"
    assert seen == [1, 2]


def test_outcome_not_in_loop_outcomes_breaks() -> None:
    seen: list[object] = []
    it = make_iterator([1, 2], collector(seen, "stop"), loop_outcomes=["continue"])
    assert it.execute() == "stop"
    assert seen == [1]


def test_final_outcome_map_maps_the_breaking_outcome() -> None:
    it = smach.Iterator(["succeeded", "done"], [], [], it=[1, 2], exhausted_outcome="done")
    it.set_contained_state(
        "BODY",
        Leaf(["continue", "found"], result="found"),
        loop_outcomes=["continue"],
        final_outcome_map={"found": "succeeded"},
    )
    assert it.execute() == "succeeded"


def test_callable_items_are_evaluated_on_every_run() -> None:
    calls: list[int] = []

    def items() -> list[int]:
        calls.append(1)
        return [len(calls)]

    seen: list[object] = []
    it = make_iterator(items, collector(seen), loop_outcomes=["continue"])
    it.execute()
    it.execute()
    assert seen == [1, 2]


def test_generator_raising_is_reported_as_user_code_error() -> None:
    def gen():  # type: ignore[no-untyped-def]
        yield 1
        raise ValueError("broken generator")

    seen: list[object] = []
    it = make_iterator(gen(), collector(seen), loop_outcomes=["continue"])
    with pytest.raises(smach.InvalidUserCodeError) as info:
        it.execute()
    assert "broken generator" in str(info.value)
    assert seen == [1]


def test_non_iterable_items_raise_user_code_error() -> None:
    it = make_iterator(42, Leaf(["continue"]), loop_outcomes=["continue"])
    with pytest.raises(smach.InvalidUserCodeError):
        it.execute()


def test_set_iteritems_and_custom_it_label() -> None:
    seen: list[object] = []

    def body(s: Fn, ud: object) -> str:
        seen.append(ud.item)  # type: ignore[attr-defined]
        return "continue"

    it = smach.Iterator(["done"], [], [], exhausted_outcome="done")
    with it:
        smach.Iterator.set_iteritems(["a", "b"], it_label="item")
        smach.Iterator.set_contained_state(
            "BODY", Fn(body, ["continue"], input_keys=["item"]), loop_outcomes=["continue"]
        )
    assert it.execute() == "done"
    assert seen == ["a", "b"]
    assert it.userdata.item == "b"


def test_contained_state_must_declare_it_label_to_read_it() -> None:
    def body(s: Fn, ud: object) -> str:
        return ud.it_data  # type: ignore[attr-defined,no-any-return]

    it = make_iterator([1], Fn(body, ["continue"]), loop_outcomes=["continue"])
    with pytest.raises(smach.InvalidUserCodeError) as info:
        it.execute()
    assert "it_data" in str(info.value)


def test_contained_state_remapping() -> None:
    def body(s: Fn, ud: object) -> str:
        ud.total += ud.x  # type: ignore[attr-defined]
        return "continue"

    it = smach.Iterator(["done"], ["total"], ["total"], it=[1, 2, 3], exhausted_outcome="done")
    it.set_contained_state(
        "SUM",
        Fn(body, ["continue"], input_keys=["x"], io_keys=["total"]),
        loop_outcomes=["continue"],
        remapping={"x": "it_data"},
    )
    parent = smach.UserData()
    parent.total = 10
    assert it.execute(parent) == "done"
    assert parent.total == 16


def test_exhausted_outcome_is_added_without_mutating_callers_list() -> None:
    outcomes = ["succeeded"]
    it = smach.Iterator(outcomes, [], [], exhausted_outcome="exhausted")
    assert outcomes == ["succeeded"]
    assert set(it.get_registered_outcomes()) == {"succeeded", "exhausted"}


def test_loop_and_break_outcomes_together_are_rejected() -> None:
    it = smach.Iterator(["done"], [], [], exhausted_outcome="done")
    with pytest.raises(smach.InvalidStateError):
        it.set_contained_state("S", Leaf(["a", "b"]), loop_outcomes=["a"], break_outcomes=["b"])


def test_unknown_loop_outcome_is_rejected() -> None:
    it = smach.Iterator(["done"], [], [], exhausted_outcome="done")
    with pytest.raises(smach.InvalidStateError):
        it.set_contained_state("S", Leaf(["a"]), loop_outcomes=["zzz"])


def test_callbacks_start_per_iteration_transition_and_termination() -> None:
    record: list[object] = []
    it = make_iterator([1, 2, 3], collector([]), loop_outcomes=["continue"])
    it.register_start_cb(lambda ud, initial: record.append(("start", initial)))
    it.register_transition_cb(lambda ud, active: record.append(("transition", active)))
    it.register_termination_cb(lambda ud, terminal, outcome: record.append(("end", outcome)))
    it.execute()
    assert record[0] == ("start", ["BODY"])
    # After every iteration that continues the loop.
    assert record[1:-1] == [("transition", ["BODY"])] * 3
    assert record[-1] == ("end", "done")


def test_active_states_while_running_and_when_idle() -> None:
    seen: list[list[str]] = []
    it = smach.Iterator(["done"], [], [], it=[1], exhausted_outcome="done")
    it.set_contained_state(
        "BODY",
        Fn(lambda s, ud: seen.append(it.get_active_states()) or "continue", ["continue"]),
        loop_outcomes=["continue"],
    )
    assert it.get_active_states() == []
    it.execute()
    assert seen == [["BODY"]]
    assert it.get_active_states() == []
    assert it.get_initial_states() == ["BODY"]
    assert it.get_children() == {"BODY": it["BODY"]}


def test_internal_edges_for_loop_and_break_outcomes() -> None:
    it = smach.Iterator(["done", "ok"], [], [], exhausted_outcome="done")
    it.set_contained_state(
        "S", Leaf(["again", "found"]), loop_outcomes=["again"], final_outcome_map={"found": "ok"}
    )
    edges = {tuple(e) for e in it.get_internal_edges()}
    assert edges == {("again", "S", "S"), ("found", "S", "ok")}


def test_contained_state_raising_is_user_code_error_with_path() -> None:
    def body(s: Fn, ud: object) -> str:
        raise RuntimeError("item failed")

    it = make_iterator([1], Fn(body, ["continue"]), loop_outcomes=["continue"])
    with pytest.raises(smach.InvalidUserCodeError) as info:
        it.execute()
    assert "item failed" in str(info.value)
    assert "BODY" in str(info.value)
    assert not it.is_running()


def test_iterator_without_contained_state_fails_consistency() -> None:
    it = smach.Iterator(["done"], [], [], exhausted_outcome="done")
    with pytest.raises(smach.InvalidTransitionError), it:
        smach.Iterator.set_iteritems([1])
    with pytest.raises(smach.InvalidTransitionError):
        it.execute()


def test_iterator_inside_statemachine_with_output_keys() -> None:
    def body(s: Fn, ud: object) -> str:
        ud.last = ud.it_data  # type: ignore[attr-defined]
        return "continue"

    it = smach.Iterator(["done"], [], ["last"], it=["x", "y"], exhausted_outcome="done")
    it.set_contained_state(
        "B",
        Fn(body, ["continue"], input_keys=["it_data"], output_keys=["last"]),
        loop_outcomes=["continue"],
    )
    sm = smach.StateMachine(["finished"])
    sm.add("IT", it, {"done": "finished"})
    assert sm.execute() == "finished"
    assert sm.userdata.last == "y"


def test_shutdown_stops_iterating_without_raising() -> None:
    # The original returns its current outcome on shutdown; a StateMachine returns None.
    seen: list[object] = []

    def body(s: Fn, ud: object) -> str:
        seen.append(ud.it_data)  # type: ignore[attr-defined]
        smach.set_shutdown_check(lambda: True)
        return "continue"

    it = make_iterator(
        [1, 2, 3], Fn(body, ["continue"], input_keys=["it_data"]), loop_outcomes=["continue"]
    )
    assert it.execute() in (None, "continue")
    assert seen == [1]


def test_iterator_can_run_twice() -> None:
    seen: list[object] = []
    it = make_iterator([1, 2], collector(seen), loop_outcomes=["continue"])
    it.execute()
    it.execute()
    assert seen == [1, 2, 1, 2]
