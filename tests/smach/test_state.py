"""smach.State and smach.CBState: interface, execute, preemption primitives."""

from __future__ import annotations

import threading
import time

import pytest
from smach_helpers import HANG, Leaf, join, start_thread

import smach


def test_state_registers_outcomes_and_keys_in_given_order() -> None:
    s = smach.State(outcomes=["b", "a"], input_keys=["y", "x"], output_keys=["z"])
    assert s.get_registered_outcomes() == ("b", "a")
    assert s.get_registered_input_keys() == ("y", "x")
    assert s.get_registered_output_keys() == ("z",)


def test_state_getters_return_tuples() -> None:
    s = smach.State(outcomes=["done"], input_keys=["a"], output_keys=["b"])
    assert isinstance(s.get_registered_outcomes(), tuple)
    assert isinstance(s.get_registered_input_keys(), tuple)
    assert isinstance(s.get_registered_output_keys(), tuple)


def test_state_defaults_are_empty() -> None:
    s = smach.State()
    assert s.get_registered_outcomes() == ()
    assert s.get_registered_input_keys() == ()
    assert s.get_registered_output_keys() == ()


def test_state_io_keys_are_both_input_and_output() -> None:
    s = smach.State(outcomes=["done"], input_keys=["a"], output_keys=["b"], io_keys=["c"])
    assert set(s.get_registered_input_keys()) == {"a", "c"}
    assert set(s.get_registered_output_keys()) == {"b", "c"}


def test_state_accepts_tuples_and_lists_mixed() -> None:
    s = smach.State(outcomes=("done",), input_keys=("a",), io_keys=["b"])
    assert set(s.get_registered_input_keys()) == {"a", "b"}


def test_register_methods_add_without_duplicates() -> None:
    s = smach.State(outcomes=["a"], input_keys=["k"])
    s.register_outcomes(["b", "a"])
    s.register_input_keys(["k", "m"])
    s.register_output_keys(["o"])
    s.register_io_keys(["io"])
    assert s.get_registered_outcomes() == ("a", "b")
    assert s.get_registered_input_keys() == ("k", "m", "io")
    assert s.get_registered_output_keys() == ("o", "io")


def test_register_accepts_any_iterable() -> None:
    s = smach.State()
    s.register_outcomes(o for o in ["x", "y"])
    s.register_input_keys({"k"})
    assert s.get_registered_outcomes() == ("x", "y")
    assert s.get_registered_input_keys() == ("k",)


def test_base_execute_raises_not_implemented() -> None:
    with pytest.raises(NotImplementedError):
        smach.State(outcomes=["done"]).execute(smach.UserData())


def test_subclass_execute_returns_outcome() -> None:
    assert Leaf(["done", "failed"], result="failed").execute(smach.UserData()) == "failed"


def test_preempt_flag_request_service_recall() -> None:
    s = Leaf()
    assert not s.preempt_requested()
    s.request_preempt()
    assert s.preempt_requested()
    s.service_preempt()
    assert not s.preempt_requested()
    s.request_preempt()
    s.recall_preempt()
    assert not s.preempt_requested()


def test_preempt_event_follows_flag() -> None:
    s = Leaf()
    event = s.preempt_event
    assert isinstance(event, threading.Event)
    assert not event.is_set()
    s.request_preempt()
    assert event.is_set()
    s.service_preempt()
    assert not event.is_set()
    s.request_preempt()
    s.recall_preempt()
    assert not event.is_set()


def test_preempt_event_created_after_request_is_already_set() -> None:
    s = Leaf()
    s.request_preempt()
    assert s.preempt_event.is_set()


def test_preempt_event_is_the_same_object_every_time() -> None:
    s = Leaf()
    assert s.preempt_event is s.preempt_event


def test_sleep_returns_false_when_not_preempted() -> None:
    assert smach.State().sleep(0) is False


def test_sleep_returns_true_at_once_when_already_preempted() -> None:
    s = smach.State()
    s.request_preempt()
    t0 = time.monotonic()
    assert s.sleep(60) is True
    assert time.monotonic() - t0 < HANG


@pytest.mark.timeout(10)
def test_sleep_wakes_up_on_request_from_other_thread() -> None:
    s = smach.State()
    result: list[bool] = []
    sleeper = start_thread(lambda: result.append(s.sleep(60)))
    # Wait until the sleeper is blocked on the event, then preempt.
    while not s._preempt_event:
        time.sleep(0.001)
    s.request_preempt()
    join(sleeper)
    assert result == [True]


def test_sleep_does_not_service_the_request() -> None:
    s = smach.State()
    s.request_preempt()
    s.sleep(1)
    assert s.preempt_requested()


def test_unattached_state_has_empty_path() -> None:
    assert smach.State().path == ""


def test_state_repr_names_class_and_outcomes() -> None:
    text = repr(Leaf(["done", "failed"]))
    assert "Leaf" in text
    assert "failed" in text


# -- CBState -------------------------------------------------------------------------------


def test_cbstate_calls_cb_with_userdata_args_and_kwargs() -> None:
    calls = []

    def cb(ud, a, b, c=None):
        calls.append((ud, a, b, c))
        return "done"

    state = smach.CBState(cb, cb_args=[1, 2], cb_kwargs={"c": 3}, outcomes=["done"])
    ud = smach.UserData()
    assert state.execute(ud) == "done"
    assert calls == [(ud, 1, 2, 3)]


def test_cbstate_keyword_defaults() -> None:
    state = smach.CBState(lambda ud: "x", outcomes=["x"])
    assert state.execute(smach.UserData()) == "x"
    assert state.get_registered_input_keys() == ()


def test_cbstate_merges_cb_interface() -> None:
    @smach.cb_interface(outcomes=["ok"], input_keys=["a"], output_keys=["b"], io_keys=["c"])
    def cb(ud):
        return "ok"

    state = smach.CBState(cb, outcomes=["extra"], input_keys=["i"])
    assert set(state.get_registered_outcomes()) == {"ok", "extra"}
    assert set(state.get_registered_input_keys()) == {"a", "c", "i"}
    assert set(state.get_registered_output_keys()) == {"b", "c"}


def test_cbstate_rejects_non_callable() -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.CBState("not callable", outcomes=["done"])  # type: ignore[arg-type]
