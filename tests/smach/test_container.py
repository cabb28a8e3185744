"""smach.Container: construction stack, construction methods, callbacks, events, paths."""

from __future__ import annotations

import contextlib
import copy
import threading

import pytest
from smach_helpers import Fn, Leaf, LogRecorder, join, start_thread

import smach
from smach.introspection import events as ev
from smach.introspection.summary import Summary


def simple_sm() -> smach.StateMachine:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["go"]), {"go": "B"})
        smach.StateMachine.add("B", Leaf(["done"]))
    return sm


# -- construction stack -------------------------------------------------------------------


def test_with_block_returns_the_container() -> None:
    sm = smach.StateMachine(["done"])
    with sm as opened:
        assert opened is sm
        smach.StateMachine.add("A", Leaf())


def test_class_level_add_acts_on_the_open_container() -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf())
    assert list(sm.get_children()) == ["A"]


def test_nested_with_blocks_add_to_the_innermost_container() -> None:
    outer = smach.StateMachine(["done"])
    inner = smach.StateMachine(["done"])
    with outer:
        with inner:
            smach.StateMachine.add("IN", Leaf())
        smach.StateMachine.add("SUB", inner)
        smach.StateMachine.add("AFTER", Leaf())
    assert list(inner.get_children()) == ["IN"]
    assert list(outer.get_children()) == ["SUB", "AFTER"]


def test_reopening_an_open_container_is_allowed() -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["go"]), {"go": "B"})
        with sm:
            smach.StateMachine.add("B", Leaf())
    assert list(sm.get_children()) == ["A", "B"]
    assert sm.execute() == "done"


def test_exception_in_with_block_unwinds_the_construction_stack() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(RuntimeError), sm:
        raise RuntimeError("boom")
    assert not sm.is_opened()
    with pytest.raises(smach.SmachError):
        smach.StateMachine.add("A", Leaf())


def test_exception_in_inner_with_block_leaves_outer_open() -> None:
    outer = smach.StateMachine(["done"])
    inner = smach.StateMachine(["done"])
    with outer:
        with pytest.raises(ValueError), inner:
            raise ValueError("inner failed")
        assert outer.is_opened()
        smach.StateMachine.add("A", Leaf())
    assert list(outer.get_children()) == ["A"]
    assert inner.get_children() == {}


def test_failed_add_inside_with_block_unwinds_the_stack() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidStateError), sm:
        smach.StateMachine.add("A", Leaf())
        smach.StateMachine.add("A", Leaf())
    assert not smach.Container._any_containers_opened()


def test_close_out_of_order_raises_invalid_state_error() -> None:
    a = smach.StateMachine(["done"])
    b = smach.StateMachine(["done"])
    a.open()
    b.open()
    with pytest.raises(smach.InvalidStateError):
        a.close()
    # Clean up in the right order (b is empty, so closing it reports that).
    with pytest.raises(smach.InvalidTransitionError):
        b.close()
    with pytest.raises(smach.InvalidTransitionError):
        a.close()
    assert not smach.Container._any_containers_opened()


def test_close_with_nothing_open_raises_invalid_state_error() -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.StateMachine(["done"]).close()


def test_opened_context_manager_yields_the_container() -> None:
    sm = smach.StateMachine(["done"])
    with sm.opened(group="ignored") as opened:
        assert opened is sm
        smach.StateMachine.add("A", Leaf())
    assert not sm.is_opened()
    assert sm.execute() == "done"


def test_is_opened_and_assert_opened() -> None:
    sm = smach.StateMachine(["done"])
    assert not sm.is_opened()
    with pytest.raises(smach.InvalidConstructionError):
        sm.assert_opened()
    with sm:
        assert sm.is_opened()
        sm.assert_opened()
        smach.StateMachine.add("A", Leaf())


@pytest.mark.timeout(10)
def test_construction_stack_is_per_thread() -> None:
    sm = smach.StateMachine(["done"])
    errors: list[BaseException] = []
    built: list[smach.StateMachine] = []

    def other_thread() -> None:
        try:
            smach.StateMachine.add("X", Leaf())
        except smach.SmachError as exc:
            errors.append(exc)
        # Building a container here works although the main thread holds one open.
        mine = smach.StateMachine(["done"])
        with mine:
            smach.StateMachine.add("T", Leaf())
        built.append(mine)

    with sm:
        smach.StateMachine.add("A", Leaf())
        join(start_thread(other_thread))
    assert len(errors) == 1
    assert list(sm.get_children()) == ["A"]
    assert list(built[0].get_children()) == ["T"]


# -- construction_method: class vs instance -----------------------------------------------------


def test_instance_add_acts_on_that_instance_even_if_another_is_open() -> None:
    open_sm = smach.StateMachine(["done"])
    other = smach.StateMachine(["done"])
    with open_sm:
        smach.StateMachine.add("A", Leaf())
        other.add("B", Leaf())
    assert list(open_sm.get_children()) == ["A"]
    assert list(other.get_children()) == ["B"]


def test_instance_add_works_without_with_block() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["go"]), {"go": "B"})
    sm.add("B", Leaf())
    assert sm.execute() == "done"


def test_class_level_add_with_no_container_open_raises_invalid_state_error() -> None:
    # The original raises InvalidStateError here (container.py:262-273).
    with pytest.raises(smach.InvalidStateError):
        smach.StateMachine.add("A", Leaf())


def test_class_level_add_with_no_container_open_is_a_smach_error() -> None:
    with pytest.raises(smach.SmachError):
        smach.Concurrence.add("A", Leaf())


def test_class_level_add_of_wrong_container_type_raises_invalid_state_error() -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf())
        with pytest.raises(smach.InvalidStateError):
            smach.Concurrence.add("B", Leaf())
        with pytest.raises(smach.InvalidStateError):
            smach.Sequence.add("C", Leaf())
    assert list(sm.get_children()) == ["A"]


def test_statemachine_add_on_open_sequence_skips_auto_linking() -> None:
    seq = smach.Sequence(["succeeded", "other"], connector_outcome="succeeded")
    with seq:
        smach.StateMachine.add("A", Leaf(["succeeded"]), {"succeeded": "other"})
        smach.Sequence.add("B", Leaf(["succeeded"]))
    assert seq._transitions["A"]["succeeded"] == "other"
    assert seq.execute() == "other"


def test_construction_method_keeps_name_and_doc() -> None:
    assert smach.StateMachine.add.__name__ == "add"
    assert "initial state" in (smach.StateMachine.add.__doc__ or "")


# -- children, labels, paths ---------------------------------------------------------------------


def test_children_get_paths_under_root() -> None:
    leaf = Leaf()
    inner_leaf = Leaf()
    sub = smach.StateMachine(["done"])
    with sub:
        smach.StateMachine.add("X", inner_leaf)
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", leaf, {"done": "SUB"})
        smach.StateMachine.add("SUB", sub)
    assert sm.path == "/ROOT"
    assert leaf.path == "/ROOT/A"
    assert sub.path == "/ROOT/SUB"
    assert inner_leaf.path == "/ROOT/SUB/X"


def test_set_root_path_renames_the_whole_tree() -> None:
    sub = smach.StateMachine(["done"])
    leaf = Leaf()
    with sub:
        smach.StateMachine.add("X", leaf)
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("SUB", sub)
    sm.set_root_path("/SM_ROOT")
    assert leaf.path == "/SM_ROOT/SUB/X"
    with pytest.raises(smach.InvalidStateError):
        sm.set_root_path("no_slash")


@pytest.mark.parametrize("label", ["", "a/b", None, 3])
def test_bad_labels_are_rejected(label: object) -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidStateError):
        sm.add(label, Leaf())  # type: ignore[arg-type]
    assert sm.get_children() == {}


def test_non_state_child_is_rejected() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidStateError):
        sm.add("A", object())  # type: ignore[arg-type]


def test_getitem_returns_child_and_unknown_label_lists_children() -> None:
    sm = simple_sm()
    assert sm["A"] is sm.get_children()["A"]
    with pytest.raises(KeyError) as info:
        sm["Z"]
    assert "A" in str(info.value)
    assert "B" in str(info.value)


def test_base_container_interface_is_abstract() -> None:
    c = smach.Container(["done"])
    for call in (
        c.get_children,
        c.get_initial_states,
        c.get_active_states,
        c.get_internal_edges,
        c.check_consistency,
        lambda: c.set_initial_state(["A"]),
    ):
        with pytest.raises(NotImplementedError):
            call()


# -- userdata ---------------------------------------------------------------------------------------


def test_userdata_can_be_replaced_before_execution() -> None:
    sm = smach.StateMachine(["done"], output_keys=["out"])
    sm.add(
        "A",
        Fn(
            lambda s, ud: setattr(ud, "out", ud.inp) or "done",
            input_keys=["inp"],
            output_keys=["out"],
        ),
    )
    with pytest.raises(smach.InvalidUserCodeError):
        sm.execute()  # compiles the remappers over the first userdata, where inp is missing
    new = smach.UserData()
    new.inp = 42
    sm.userdata = new
    parent = smach.UserData()
    assert sm.execute(parent) == "done"
    assert parent.out == 42
    assert new.out == 42


def test_userdata_setter_rejects_non_userdata() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidStateError):
        sm.userdata = {"a": 1}  # type: ignore[assignment]


# -- callbacks --------------------------------------------------------------------------------------


def test_callbacks_receive_original_argument_order_and_cb_args() -> None:
    sm = simple_sm()
    calls: list[tuple[object, ...]] = []
    sm.register_start_cb(lambda ud, initial, *a: calls.append(("start", ud, initial, a)), [1, 2])
    sm.register_transition_cb(lambda ud, active, *a: calls.append(("transition", ud, a)), [3])
    sm.register_termination_cb(
        lambda ud, terminal, outcome, *a: calls.append(("end", ud, terminal, outcome, a)), [4]
    )
    assert sm.execute() == "done"
    assert calls[0] == ("start", sm.userdata, ["A"], (1, 2))
    assert calls[1] == ("transition", sm.userdata, (3,))
    assert calls[2] == ("end", sm.userdata, ["B"], "done", (4,))
    assert len(calls) == 3


def test_callbacks_get_the_containers_local_userdata() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Fn(lambda s, ud: setattr(ud, "x", 1) or "done", output_keys=["x"]))
    seen: list[object] = []
    sm.register_termination_cb(lambda ud, terminal, outcome: seen.append(ud.x))
    sm.execute()
    assert seen == [1]


def test_several_callbacks_run_in_registration_order() -> None:
    sm = simple_sm()
    order: list[int] = []
    for i in range(3):
        sm.register_start_cb(lambda ud, init, i=i: order.append(i))
    sm.execute()
    assert order == [0, 1, 2]


def test_callbacks_are_called_on_every_execution() -> None:
    sm = simple_sm()
    starts: list[object] = []
    sm.register_start_cb(lambda ud, init: starts.append(init))
    sm.execute()
    sm.execute()
    assert starts == [["A"], ["A"]]


# -- listeners and events ----------------------------------------------------------------------------


def test_listener_receives_the_event_stream_with_paths() -> None:
    sm = simple_sm()
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    sm.execute()
    summary = [(type(e).__name__, e.path) for e in received]
    assert summary == [
        ("ContainerStarted", "/ROOT"),
        ("StateEntered", "/ROOT/A"),
        ("StateExited", "/ROOT/A"),
        ("Transition", "/ROOT"),
        ("StateEntered", "/ROOT/B"),
        ("StateExited", "/ROOT/B"),
        ("ContainerTerminated", "/ROOT"),
    ]
    transition = received[3]
    assert isinstance(transition, ev.Transition)
    assert (transition.source, transition.outcome, transition.target) == ("A", "go", "B")
    end = received[-1]
    assert isinstance(end, ev.ContainerTerminated)
    assert end.outcome == "done"
    assert end.terminal_states == ("B",)
    assert all(e.thread for e in received)
    assert [e.time for e in received] == sorted(e.time for e in received)


def test_listener_on_root_sees_nested_events() -> None:
    sub = smach.StateMachine(["done"])
    with sub:
        smach.StateMachine.add("X", Leaf())
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("SUB", sub)
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    sm.execute()
    paths = [e.path for e in received if isinstance(e, ev.StateEntered)]
    assert paths == ["/ROOT/SUB", "/ROOT/SUB/X"]


def test_listener_added_to_child_before_adoption_keeps_receiving() -> None:
    sub = smach.StateMachine(["done"])
    with sub:
        smach.StateMachine.add("X", Leaf())
    received: list[ev.Event] = []
    sub.add_listener(received.append)
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("SUB", sub)
    sm.execute()
    assert any(isinstance(e, ev.StateEntered) and e.path == "/ROOT/SUB/X" for e in received)


def test_remove_listener_stops_delivery() -> None:
    sm = simple_sm()
    received: list[ev.Event] = []

    def listener(event: ev.Event) -> None:
        received.append(event)

    sm.add_listener(listener)
    sm.remove_listener(listener)
    sm.execute()
    assert received == []


def test_remove_listener_accepts_an_equal_bound_method() -> None:
    # ``obj.method`` builds a new bound-method object on every access.
    sm = simple_sm()
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    sm.remove_listener(received.append)
    sm.execute()
    assert received == []


def test_raising_listener_is_detached_and_reported(logs: LogRecorder) -> None:
    sm = simple_sm()
    calls: list[ev.Event] = []

    def bad(event: ev.Event) -> None:
        calls.append(event)
        raise RuntimeError("listener bug")

    sm.add_listener(bad)
    assert sm.execute() == "done"
    assert len(calls) == 1
    assert any("listener bug" in m for m in logs.error)
    assert sm.execute() == "done"
    assert len(calls) == 1


def test_userdata_written_event_names_key_and_writer() -> None:
    sm = smach.StateMachine(["done"])
    sm.add(
        "W",
        Fn(lambda s, ud: setattr(ud, "out", 5) or "done", output_keys=["out"]),
        remapping={"out": "container_key"},
    )
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    sm.execute()
    written = [e for e in received if isinstance(e, ev.UserdataWritten)]
    assert len(written) == 1
    assert (written[0].key, written[0].value, written[0].writer) == ("container_key", 5, "W")
    assert written[0].path == "/ROOT"


def test_preempt_events_are_emitted() -> None:
    def body(s: Fn, ud: object) -> str:
        s.service_preempt()
        return "done"

    sm = smach.StateMachine(["done"])
    sm.add("A", Fn(body))
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    sm.request_preempt()
    sm.execute()
    kinds = {(type(e).__name__, e.path) for e in received}
    assert ("PreemptRequested", "/ROOT") in kinds
    assert ("PreemptRequested", "/ROOT/A") in kinds
    assert ("PreemptServiced", "/ROOT/A") in kinds


def test_error_event_is_emitted_when_a_child_raises() -> None:
    def body(s: Fn, ud: object) -> str:
        raise ValueError("bad")

    sm = smach.StateMachine(["done"])
    sm.add("A", Fn(body))
    received: list[ev.Event] = []
    sm.add_listener(received.append)
    with pytest.raises(smach.InvalidUserCodeError):
        sm.execute()
    errors = [e for e in received if isinstance(e, ev.ErrorRaised)]
    assert errors
    assert errors[-1].error_type == "InvalidUserCodeError"
    assert "bad" in errors[-1].message


def test_event_to_dict_contains_kind_and_fields() -> None:
    event = ev.Transition(path="/R", time=1.0, thread="t", source="A", outcome="o", target="B")
    data = event.to_dict()
    assert data["kind"] == "transition"
    assert data["source"] == "A"
    assert data["path"] == "/R"


@pytest.mark.timeout(10)
def test_is_running_is_true_only_during_execution() -> None:
    sm = smach.StateMachine(["done"])
    seen: list[bool] = []
    sm.add("A", Fn(lambda s, ud: seen.append(sm.is_running()) or "done"))
    assert not sm.is_running()
    sm.execute()
    assert seen == [True]
    assert not sm.is_running()


def test_thread_event_loop_helper_is_not_needed() -> None:
    # Containers are plain objects: building one starts no thread.
    before = threading.active_count()
    simple_sm()
    assert threading.active_count() == before


# -- capture listeners (journal, viewer) --------------------------------------------------------------


def nested_sm() -> smach.StateMachine:
    sub = smach.StateMachine(["done"], output_keys=["n"])
    with sub:
        smach.StateMachine.add(
            "X", Fn(lambda s, ud: setattr(ud, "n", 3) or "done", output_keys=["n"])
        )
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["go"]), {"go": "SUB"})
        smach.StateMachine.add("SUB", sub, {"done": "B"})
        smach.StateMachine.add("B", Leaf(["done"]))
    return sm


def test_capture_listener_gets_the_same_stream_as_tuples() -> None:
    sm = nested_sm()
    events: list[ev.Event] = []
    captures: list[ev.Capture] = []
    sm.add_listener(events.append)
    sm.add_listener(ev.CaptureListener(captures.append, captures.extend))
    sm.execute()
    assert all(type(c) is tuple and c[0] is type(e) for c, e in zip(captures, events, strict=True))
    assert [ev.event_of(c) for c in captures] == events
    assert [e.capture() for e in events] == captures


def test_capture_listener_alone_gets_every_event_one_by_one_by_default() -> None:
    # Only capture listeners: the state machine builds no Event object at all.
    captures: list[ev.Capture] = []
    watched = nested_sm()
    watched.add_listener(ev.CaptureListener(captures.append))  # no capture_many: each
    watched.execute()
    events: list[ev.Event] = []
    twin = nested_sm()
    twin.add_listener(events.append)
    twin.execute()
    assert [(c[0], c[1]) for c in captures] == [(type(e), e.path) for e in events]
    assert [c[4:] for c in captures] == [e.capture()[4:] for e in events]


def test_state_exited_and_the_following_transition_share_one_time() -> None:
    sm = simple_sm()
    events: list[ev.Event] = []
    sm.add_listener(events.append)
    sm.execute()
    exited = next(e for e in events if isinstance(e, ev.StateExited))
    transition = next(e for e in events if isinstance(e, ev.Transition))
    assert exited.time == transition.time


def test_captures_hold_a_summary_of_a_value_that_can_change() -> None:
    def write(s: Fn, ud: object) -> str:
        items = [1, 2]
        ud.items = items  # type: ignore[attr-defined]
        items.append(3)
        return "done"

    sm = smach.StateMachine(["done"])
    sm.add("W", Fn(write, output_keys=["items"]))
    events: list[ev.Event] = []
    captures: list[ev.Capture] = []
    sm.add_listener(events.append)
    sm.add_listener(ev.CaptureListener(captures.append))
    sm.execute()
    (event,) = [e for e in events if isinstance(e, ev.UserdataWritten)]
    (capture,) = [c for c in captures if c[0] is ev.UserdataWritten]
    assert event.value == [1, 2, 3]  # ordinary listeners get the live object
    assert capture[5] == Summary([1, 2])  # captures: as it was written


def test_a_raising_capture_listener_is_detached_and_reported(logs: LogRecorder) -> None:
    sm = simple_sm()
    calls: list[ev.Capture] = []

    def bad(capture: ev.Capture) -> None:
        calls.append(capture)
        raise RuntimeError("capture bug")

    listener = ev.CaptureListener(bad)
    sm.add_listener(listener)
    assert sm.execute() == "done"
    assert len(calls) == 1
    assert listener not in sm._bus.listeners
    assert any("capture bug" in m for m in logs.error)
    assert sm.execute() == "done"
    assert len(calls) == 1


def test_events_follow_a_renamed_root_after_a_run() -> None:
    sm = simple_sm()
    captures: list[ev.Capture] = []
    events: list[ev.Event] = []
    sm.add_listener(ev.CaptureListener(captures.append, captures.extend))
    sm.add_listener(events.append)
    sm.execute()
    sm.set_root_path("/SM")
    captures.clear()
    events.clear()
    sm.execute()
    assert {c[1] for c in captures} == {"/SM", "/SM/A", "/SM/B"}
    assert {e.path for e in events} == {"/SM", "/SM/A", "/SM/B"}


def _preempted_in_b() -> smach.StateMachine:
    def b(s: Fn, ud: object) -> str:
        s.service_preempt()
        return "done"

    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add(
            "A", Fn(lambda s, ud: (sm.request_preempt(), "go")[1], ["go"]), {"go": "B"}
        )
        smach.StateMachine.add("B", Fn(b))
    return sm


def _raising_in_b() -> smach.StateMachine:
    def b(s: Fn, ud: object) -> str:
        raise ValueError("bad")

    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["go"]), {"go": "B"})
        smach.StateMachine.add("B", Fn(b))
    return sm


def _shutdown_after_a() -> smach.StateMachine:
    flag = {"down": False}

    def a(s: Fn, ud: object) -> str:
        flag["down"] = True
        return "go"

    smach.set_shutdown_check(lambda: flag["down"])
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Fn(a, ["go"]), {"go": "B"})
        smach.StateMachine.add("B", Leaf())
    return sm


def _shutdown_check_raises_after_a() -> smach.StateMachine:
    flag = {"broken": False}

    def a(s: Fn, ud: object) -> str:
        flag["broken"] = True
        return "go"

    def check() -> bool:
        if flag["broken"]:
            raise RuntimeError("shutdown check broke")
        return False

    smach.set_shutdown_check(check)
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Fn(a, ["go"]), {"go": "B"})
        smach.StateMachine.add("B", Leaf())
    return sm


def _listener_joins_in_a() -> smach.StateMachine:
    sm = smach.StateMachine(["done"])
    late: list[ev.Event] = []
    with sm:
        smach.StateMachine.add(
            "A", Fn(lambda s, ud: (sm.add_listener(late.append), "go")[1], ["go"]), {"go": "B"}
        )
        smach.StateMachine.add("B", Leaf(["go"]), {"go": "C"})
        smach.StateMachine.add("C", Leaf())
    return sm


@pytest.mark.parametrize(
    "build",
    [
        _preempted_in_b,
        _raising_in_b,
        _shutdown_after_a,
        _shutdown_check_raises_after_a,
        _listener_joins_in_a,
    ],
)
def test_capture_listeners_see_what_ordinary_listeners_see_in_the_same_order(
    build: object,
) -> None:
    # Capture listeners alone get a step's events together when the next state starts;
    # preemption, errors, shutdown and listeners joining must not reorder or lose any.
    def run(listener: object) -> None:
        sm = build()  # type: ignore[operator]
        sm.add_listener(listener)
        with contextlib.suppress(smach.InvalidUserCodeError, RuntimeError):
            sm.execute()

    captures: list[ev.Capture] = []
    run(ev.CaptureListener(captures.append, captures.extend))
    events: list[ev.Event] = []
    run(events.append)
    assert [(c[0].kind, c[1]) for c in captures] == [(e.kind, e.path) for e in events]


def test_input_and_output_keys_follow_whichever_parent_userdata_a_run_is_given() -> None:
    def bump(ud: smach.UserData) -> str:
        ud.x = ud.x + 1
        return "done"

    sm = smach.StateMachine(outcomes=["done"], input_keys=["x"], output_keys=["x"])
    sm.add("BUMP", smach.CBState(bump, outcomes=["done"], io_keys=["x"]))
    first, second = smach.UserData({"x": 1}), smach.UserData({"x": 10})
    for parent in (first, second, first):
        assert sm.execute(parent) == "done"
    assert (first.x, second.x) == (3, 11)
    outer = smach.StateMachine(outcomes=["done"])
    outer.userdata.x = 100
    outer.add("INNER", sm, remapping={"x": "x"})
    assert outer.execute() == "done"
    assert outer.userdata.x == 101


def test_a_tree_that_passed_keys_down_can_be_deep_copied_and_the_copy_runs() -> None:
    def bump(ud: smach.UserData) -> str:
        ud.x = ud.x + 1
        return "done"

    inner = smach.StateMachine(outcomes=["done"], input_keys=["x"], output_keys=["x"])
    inner.add("BUMP", smach.CBState(bump, outcomes=["done"], io_keys=["x"]))
    outer = smach.StateMachine(outcomes=["done"], input_keys=["x"], output_keys=["x"])
    outer.add("INNER", inner)
    parent = smach.UserData({"x": 1})
    assert outer.execute(parent) == "done"
    twin = copy.deepcopy(outer)
    other = smach.UserData({"x": 10})
    assert twin.execute(other) == "done"
    assert (parent.x, other.x) == (2, 11)
