"""smach.StateMachine: transitions, add/add_auto, userdata scoping, introspection."""

from __future__ import annotations

import pytest
from smach_helpers import Fn, Leaf

import smach


def chain(*labels: str) -> smach.StateMachine:
    """A machine running the given labels in order, each with outcome 'next'/'done'."""
    sm = smach.StateMachine(["done"])
    with sm:
        for i, label in enumerate(labels):
            if i + 1 < len(labels):
                smach.StateMachine.add(label, Leaf(["next"]), {"next": labels[i + 1]})
            else:
                smach.StateMachine.add(label, Leaf(["done"]))
    return sm


def test_runs_states_along_transitions() -> None:
    sm = chain("A", "B", "C")
    assert sm.execute() == "done"
    assert [sm[label].calls for label in "ABC"] == [1, 1, 1]  # type: ignore[attr-defined]


def test_first_added_state_is_initial() -> None:
    sm = chain("FIRST", "SECOND")
    assert sm.get_initial_states() == ["FIRST"]


def test_missing_transition_falls_through_as_container_outcome() -> None:
    sm = smach.StateMachine(["done", "failed"])
    with sm:
        smach.StateMachine.add("A", Leaf(["ok", "failed"], result="failed"), {"ok": "done"})
    assert sm.execute() == "failed"


@pytest.mark.parametrize("terminal", [None, ""])
def test_none_and_empty_string_targets_are_terminal(terminal: str | None) -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["done"]), {"done": terminal})
    assert sm.execute() == "done"


def test_transition_to_container_outcome_returns_it() -> None:
    sm = smach.StateMachine(["finished"])
    with sm:
        smach.StateMachine.add("A", Leaf(["ok"]), {"ok": "finished"})
    assert sm.execute() == "finished"


def test_state_outcome_may_share_a_name_with_a_state_label() -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["B"]), {"B": "B"})
        smach.StateMachine.add("B", Leaf(["done"]))
    assert sm.execute() == "done"


def test_loops_until_an_outcome_leaves() -> None:
    counter = {"n": 0}

    def body(s: Fn, ud: object) -> str:
        counter["n"] += 1
        return "again" if counter["n"] < 5 else "done"

    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("LOOP", Fn(body, ["again", "done"]), {"again": "LOOP"})
    assert sm.execute() == "done"
    assert counter["n"] == 5


def test_add_returns_the_state() -> None:
    sm = smach.StateMachine(["done"])
    leaf = Leaf()
    with sm:
        assert smach.StateMachine.add("A", leaf) is leaf


def test_add_does_not_mutate_callers_transitions() -> None:
    transitions = {"ok": "B"}
    remapping = {"a": "b"}
    sm = smach.StateMachine(["done", "failed"])
    with sm:
        smach.StateMachine.add("A", Leaf(["ok", "failed"]), transitions, remapping)
        smach.StateMachine.add("B", Leaf(["done"]))
    assert transitions == {"ok": "B"}
    assert remapping == {"a": "b"}


def test_set_initial_state_changes_where_the_run_starts() -> None:
    sm = chain("A", "B")
    sm.set_initial_state(["B"])
    assert sm.get_initial_states() == ["B"]
    assert sm.execute() == "done"
    assert sm["A"].calls == 0  # type: ignore[attr-defined]


def test_set_initial_state_merges_userdata() -> None:
    sm = chain("A", "B")
    ud = smach.UserData()
    ud.x = 1
    sm.set_initial_state(["A"], ud)
    assert sm.userdata.x == 1


def test_set_initial_state_unknown_label_is_reported_at_execute() -> None:
    sm = chain("A")
    sm.set_initial_state(["NOPE"])  # checked with the other consistency checks
    with pytest.raises(smach.InvalidTransitionError, match="initial state 'NOPE'"):
        sm.execute()


def test_set_initial_state_may_name_a_state_added_later() -> None:
    sm = smach.StateMachine(["done"])
    with sm:
        sm.set_initial_state(["B"])
        smach.StateMachine.add("A", Leaf(["done"]))
        smach.StateMachine.add("B", Leaf(["done"]))
    assert sm.get_initial_states() == ["B"]
    assert sm.execute() == "done"
    assert sm["A"].calls == 0  # type: ignore[attr-defined]


def test_set_initial_state_unknown_label_is_reported_at_close() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidTransitionError, match="initial state 'NOPE'"), sm:
        sm.set_initial_state(["NOPE"])
        smach.StateMachine.add("A", Leaf(["done"]))


def test_execute_can_be_repeated() -> None:
    sm = chain("A", "B")
    assert sm.execute() == "done"
    assert sm.execute() == "done"
    assert sm["B"].calls == 2  # type: ignore[attr-defined]


def test_reentrant_execute_of_a_running_machine_raises() -> None:
    sm = smach.StateMachine(["done"])
    errors: list[BaseException] = []

    def body(s: Fn, ud: object) -> str:
        try:
            sm.execute()
        except smach.InvalidStateError as exc:
            errors.append(exc)
        return "done"

    sm.add("A", Fn(body))
    assert sm.execute() == "done"
    assert len(errors) == 1
    assert not sm.is_running()


# -- add_auto ----------------------------------------------------------------------------------


def test_add_auto_links_connectors_to_the_next_state() -> None:
    sm = smach.StateMachine(["done", "failed"])
    with sm:
        smach.StateMachine.add_auto("A", Leaf(["ok", "failed"]), ["ok"])
        smach.StateMachine.add_auto("B", Leaf(["ok", "failed"]), ["ok"])
        smach.StateMachine.add("C", Leaf(["done"]))
    assert sm._transitions["A"]["ok"] == "B"
    assert sm._transitions["B"]["ok"] == "C"
    assert sm._transitions["A"]["failed"] is None
    assert sm.execute() == "done"


def test_add_auto_explicit_transitions_win_over_connectors() -> None:
    sm = smach.StateMachine(["done", "skipped"])
    with sm:
        smach.StateMachine.add_auto("A", Leaf(["ok"]), ["ok"], transitions={"ok": "skipped"})
        smach.StateMachine.add("B", Leaf(["done"]))
    assert sm._transitions["A"]["ok"] == "skipped"
    assert sm.execute() == "skipped"


def test_last_add_auto_state_falls_through_on_its_connectors() -> None:
    sm = smach.StateMachine(["ok"])
    with sm:
        smach.StateMachine.add_auto("A", Leaf(["ok"]), ["ok"])
    assert sm.execute() == "ok"


def test_add_auto_rejects_unregistered_connector() -> None:
    sm = smach.StateMachine(["done"])
    with pytest.raises(smach.InvalidStateError), sm:
        smach.StateMachine.add_auto("A", Leaf(["done"]), ["nope"])


def test_add_auto_does_not_mutate_connector_list() -> None:
    connectors = ["ok"]
    sm = smach.StateMachine(["ok"])
    sm.add_auto("A", Leaf(["ok"]), connectors)
    assert connectors == ["ok"]


# -- constants, remapping, userdata scoping ----------------------------------------------------


def test_constants_are_written_before_every_execution_of_the_state() -> None:
    seen: list[object] = []

    def reader(s: Fn, ud: object) -> str:
        seen.append(ud.c)  # type: ignore[attr-defined]
        return "again" if len(seen) < 2 else "done"

    def clobber(s: Fn, ud: object) -> str:
        ud.c = "clobbered"  # type: ignore[attr-defined]
        return "back"

    sm = smach.StateMachine(["done"])
    sm.add(
        "R",
        Fn(reader, ["again", "done"], input_keys=["c"]),
        {"again": "W"},
        constants={"c": "const"},
    )
    sm.add("W", Fn(clobber, ["back"], output_keys=["c"]), {"back": "R"})
    assert sm.execute() == "done"
    assert seen == ["const", "const"]


def test_remapping_translates_state_keys_to_container_keys() -> None:
    def body(s: Fn, ud: object) -> str:
        ud.result = ud.arg * 2  # type: ignore[attr-defined]
        return "done"

    sm = smach.StateMachine(["done"])
    sm.add(
        "A",
        Fn(body, input_keys=["arg"], output_keys=["result"]),
        remapping={"arg": "x", "result": "y"},
    )
    sm.userdata.x = 21
    assert sm.execute() == "done"
    assert sm.userdata.y == 42
    assert "result" not in sm.userdata


def test_userdata_set_before_execute_is_kept() -> None:
    sm = smach.StateMachine(["done", "bad"], input_keys=["x"])
    sm.add("A", Fn(lambda s, ud: "done" if ud.x == 1 else "bad", ["done", "bad"], input_keys=["x"]))
    sm.userdata.x = 1
    assert sm.execute() == "done"
    # A parent that lacks the key does not erase the local value.
    assert sm.execute(smach.UserData()) == "done"


def test_input_keys_copied_in_and_output_keys_copied_out() -> None:
    def body(s: Fn, ud: object) -> str:
        ud.out = ud.inp + 1  # type: ignore[attr-defined]
        ud.local_only = "x"  # type: ignore[attr-defined]
        return "done"

    sm = smach.StateMachine(["done"], input_keys=["inp"], output_keys=["out"])
    sm.add("A", Fn(body, input_keys=["inp"], output_keys=["out", "local_only"]))
    parent = smach.UserData()
    parent.inp = 1
    assert sm.execute(parent) == "done"
    assert parent.out == 2
    assert "local_only" not in parent
    assert sm.userdata.local_only == "x"


def test_nested_machine_scoping_goes_through_parent_remapping() -> None:
    def body(s: Fn, ud: object) -> str:
        ud.inner_out = ud.inner_in + "!"  # type: ignore[attr-defined]
        return "done"

    sub = smach.StateMachine(["done"], input_keys=["inner_in"], output_keys=["inner_out"])
    sub.add("LEAF", Fn(body, input_keys=["inner_in"], output_keys=["inner_out"]))
    sm = smach.StateMachine(["done"])
    sm.add("SUB", sub, remapping={"inner_in": "request", "inner_out": "response"})
    sm.userdata.request = "hi"
    assert sm.execute() == "done"
    assert sm.userdata.response == "hi!"
    assert "inner_out" not in sm.userdata


def test_values_are_shared_by_reference_across_scopes() -> None:
    shared: list[str] = []

    def body(s: Fn, ud: object) -> str:
        ud.bag.append("child")  # type: ignore[attr-defined]
        return "done"

    sub = smach.StateMachine(["done"], input_keys=["bag"])
    sub.add("LEAF", Fn(body, io_keys=["bag"]))
    sm = smach.StateMachine(["done"])
    sm.add("SUB", sub)
    sm.userdata.bag = shared
    sm.execute()
    assert shared == ["child"]
    assert sub.userdata.bag is shared


def test_missing_parent_input_key_warns(logs) -> None:  # type: ignore[no-untyped-def]
    sm = smach.StateMachine(["done"], input_keys=["absent"])
    sm.add("A", Leaf())
    assert sm.execute(smach.UserData()) == "done"
    assert any("absent" in m for m in logs.warn)


def test_leaf_registering_keys_after_a_run_is_honoured() -> None:
    # The original builds the Remapper from the registered keys on every execution.
    class Late(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["done"])

        def execute(self, ud: object) -> str:
            if "y" in self.get_registered_output_keys():
                ud.y = 1  # type: ignore[attr-defined]
            return "done"

    late = Late()
    sm = smach.StateMachine(["done"])
    sm.add("L", late)
    sm.execute()
    late.register_output_keys(["y"])
    assert sm.execute() == "done"
    assert sm.userdata.y == 1


def test_container_registering_keys_after_construction_is_honoured() -> None:
    sub = smach.StateMachine(["done", "bad"])
    sub.add(
        "LEAF", Fn(lambda s, ud: "done" if ud.k == 1 else "bad", ["done", "bad"], input_keys=["k"])
    )
    sm = smach.StateMachine(["done", "bad"])
    sm.add("SUB", sub)
    sm.userdata.k = 1
    sub.register_input_keys(["k"])
    assert sm.execute() == "done"


# -- shutdown -------------------------------------------------------------------------------------


def test_shutdown_between_states_returns_none() -> None:
    flags = {"down": False}
    smach.set_shutdown_check(lambda: flags["down"])

    def first(s: Fn, ud: object) -> str:
        flags["down"] = True
        return "next"

    sm = smach.StateMachine(["done"])
    sm.add("A", Fn(first, ["next"]), {"next": "B"})
    second = Leaf()
    sm.add("B", second)
    assert sm.execute() is None
    assert second.calls == 0
    assert not sm.is_running()


def test_shutdown_before_start_runs_nothing() -> None:
    smach.set_shutdown_check(lambda: True)
    sm = chain("A")
    assert sm.execute() is None
    assert sm["A"].calls == 0  # type: ignore[attr-defined]


# -- introspection --------------------------------------------------------------------------------


def test_active_states_during_and_after_run() -> None:
    sm = smach.StateMachine(["done"])
    seen: list[list[str]] = []
    sm.add(
        "A",
        Fn(lambda s, ud: seen.append(sm.get_active_states()) or "next", ["next"]),
        {"next": "B"},
    )
    sm.add("B", Fn(lambda s, ud: seen.append(sm.get_active_states()) or "done"))
    assert sm.get_active_states() == []
    sm.execute()
    assert seen == [["A"], ["B"]]
    assert sm.get_active_states() == []


def test_transition_callback_sees_the_new_active_state() -> None:
    sm = chain("A", "B", "C")
    seen: list[list[str]] = []
    sm.register_transition_cb(lambda ud, active: seen.append(list(active)))
    sm.execute()
    assert seen == [["B"], ["C"]]


def test_start_and_termination_callback_states() -> None:
    sm = chain("A", "B")
    record: list[object] = []
    sm.register_start_cb(lambda ud, initial: record.append(("start", initial)))
    sm.register_termination_cb(lambda ud, terminal, outcome: record.append((terminal, outcome)))
    sm.execute()
    assert record == [("start", ["A"]), (["B"], "done")]


def test_get_internal_edges_lists_every_transition() -> None:
    sm = smach.StateMachine(["done", "failed"])
    with sm:
        smach.StateMachine.add("A", Leaf(["ok", "failed"]), {"ok": "B"})
        smach.StateMachine.add("B", Leaf(["done"]), {"done": ""})
    assert sorted(sm.get_internal_edges(), key=str) == sorted(
        [("ok", "A", "B"), ("failed", "A", None), ("done", "B", None)], key=str
    )


def test_get_children_maps_labels_to_states() -> None:
    sm = chain("A", "B")
    children = sm.get_children()
    assert list(children) == ["A", "B"]
    assert all(isinstance(s, Leaf) for s in children.values())


def test_check_consistency_passes_for_valid_machine() -> None:
    sm = chain("A", "B")
    sm.check_consistency()
    assert sm.consistency_problems() == []


def test_statemachine_is_a_state_with_declared_interface() -> None:
    sm = smach.StateMachine(["a", "b"], input_keys=["i"], output_keys=["o"])
    assert isinstance(sm, smach.State)
    assert isinstance(sm, smach.Container)
    assert sm.get_registered_outcomes() == ("a", "b")
    assert sm.get_registered_input_keys() == ("i",)
    assert sm.get_registered_output_keys() == ("o",)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_statemachine_can_be_pickled_and_deep_copied(how: str) -> None:
    # The original supports this (__getstate__/__setstate__ drop and recreate the lock, #86).
    import copy
    import pickle

    sm = chain("A", "B")
    sm.userdata.x = [1]
    clone = pickle.loads(pickle.dumps(sm)) if how == "pickle" else copy.deepcopy(sm)
    assert clone is not sm
    assert clone.userdata.x == [1]
    assert clone.execute() == "done"
    assert sm["A"].calls == 0  # type: ignore[attr-defined]
