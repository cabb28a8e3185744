"""smach.Concurrence: parallel children, outcome policy, userdata, callbacks."""

from __future__ import annotations

import threading

import pytest
from smach_helpers import HANG, Blocker, Fn, Leaf

import smach

pytestmark = pytest.mark.timeout(10)


def conc(outcomes=("done", "failed"), default="done", **kwargs) -> smach.Concurrence:  # type: ignore[no-untyped-def]
    return smach.Concurrence(list(outcomes), default, **kwargs)


def test_children_run_at_the_same_time() -> None:
    barrier = threading.Barrier(2, timeout=HANG)

    def meet(s: Fn, ud: object) -> str:
        barrier.wait()  # BrokenBarrierError (-> error) unless both run at once
        return "done"

    cc = conc()
    with cc:
        smach.Concurrence.add("A", Fn(meet))
        smach.Concurrence.add("B", Fn(meet))
    assert cc.execute() == "done"


def test_many_children_all_start_without_waiting_for_each_other() -> None:
    n = 24
    barrier = threading.Barrier(n, timeout=HANG)
    cc = conc()
    with cc:
        for i in range(n):
            smach.Concurrence.add(f"C{i}", Fn(lambda s, ud: barrier.wait() * 0 or "done"))
    assert cc.execute() == "done"


def test_nested_concurrences_all_run_at_once() -> None:
    barrier = threading.Barrier(4, timeout=HANG)

    def meet(s: Fn, ud: object) -> str:
        barrier.wait()
        return "done"

    outer = conc()
    for name in ("X", "Y"):
        inner = conc()
        inner.add("A", Fn(meet))
        inner.add("B", Fn(meet))
        outer.add(name, inner)
    assert outer.execute() == "done"


def test_default_outcome_when_no_policy_matches() -> None:
    cc = conc(outcome_map={"failed": {"A": "bad"}})
    cc.add("A", Leaf(["ok", "bad"]))
    assert cc.execute() == "done"


def test_outcome_map_match() -> None:
    cc = conc(outcome_map={"failed": {"A": "bad", "B": "bad"}})
    cc.add("A", Leaf(["ok", "bad"], result="bad"))
    cc.add("B", Leaf(["ok", "bad"], result="bad"))
    assert cc.execute() == "failed"


def test_outcome_map_requires_every_listed_child() -> None:
    cc = conc(outcome_map={"failed": {"A": "bad", "B": "bad"}})
    cc.add("A", Leaf(["ok", "bad"], result="bad"))
    cc.add("B", Leaf(["ok", "bad"], result="ok"))
    assert cc.execute() == "done"


def test_outcome_map_without_default_outcome() -> None:
    cc = smach.Concurrence(["a", "b"], None, outcome_map={"a": {"X": "x"}, "b": {"X": "y"}})
    cc.add("X", Leaf(["x", "y"], result="y"))
    assert cc.execute() == "b"


def test_no_match_and_no_default_raises() -> None:
    cc = smach.Concurrence(["a"], None, outcome_map={"a": {"X": "x"}})
    cc.add("X", Leaf(["x", "y"], result="y"))
    with pytest.raises(smach.InvalidUserCodeError):
        cc.execute()


def test_outcome_cb_receives_all_child_outcomes() -> None:
    seen: list[dict[str, str | None]] = []

    def outcome_cb(outcomes: dict[str, str | None]) -> str:
        seen.append(outcomes)
        return "failed"

    cc = conc(outcome_cb=outcome_cb)
    cc.add("A", Leaf(["a1"]))
    cc.add("B", Leaf(["b1"]))
    assert cc.execute() == "failed"
    assert seen == [{"A": "a1", "B": "b1"}]


def test_falsy_outcome_cb_result_falls_back_to_map_then_default() -> None:
    cc = conc(outcome_map={"failed": {"A": "x"}}, outcome_cb=lambda o: None)
    cc.add("A", Leaf(["x"]))
    assert cc.execute() == "failed"
    cc2 = conc(outcome_cb=lambda o: "")
    cc2.add("A", Leaf(["x"]))
    assert cc2.execute() == "done"


def test_children_share_the_container_userdata_with_remapping() -> None:
    def write_a(s: Fn, ud: object) -> str:
        ud.out = "from A"  # type: ignore[attr-defined]
        return "done"

    def read_b(s: Fn, ud: object) -> str:
        ud.copy = ud.inp  # type: ignore[attr-defined]
        return "done"

    cc = conc(input_keys=["inp"], output_keys=["a_out", "copy"])
    cc.add("A", Fn(write_a, output_keys=["out"]), remapping={"out": "a_out"})
    cc.add("B", Fn(read_b, input_keys=["inp"], output_keys=["copy"]))
    parent = smach.UserData()
    parent.inp = 7
    assert cc.execute(parent) == "done"
    assert parent.a_out == "from A"
    assert parent.copy == 7
    assert cc.userdata.a_out == "from A"


def test_concurrence_inside_statemachine() -> None:
    cc = conc(outcome_map={"failed": {"B": "bad"}})
    cc.add("A", Leaf(["ok"]))
    cc.add("B", Leaf(["ok", "bad"], result="bad"))
    sm = smach.StateMachine(["ok", "ko"])
    sm.add("CC", cc, {"done": "ok", "failed": "ko"})
    assert sm.execute() == "ko"


def test_repeated_execution_starts_with_fresh_outcomes() -> None:
    results = iter(["x", "y"])
    seen: list[dict[str, str | None]] = []
    cc = conc(outcome_cb=lambda o: seen.append(dict(o)) or "done")
    cc.add("A", Fn(lambda s, ud: next(results), ["x", "y"]))
    cc.execute()
    cc.execute()
    assert seen == [{"A": "x"}, {"A": "y"}]


def test_child_termination_cb_sees_unfinished_children_as_none() -> None:
    seen: list[dict[str, str | None]] = []
    blocker = Blocker()

    def cb(outcomes: dict[str, str | None]) -> bool:
        seen.append(dict(outcomes))
        return outcomes["FAST"] is not None

    cc = conc(["done"], child_termination_cb=cb)
    cc.add("FAST", Leaf(["done"]))
    cc.add("SLOW", blocker)
    assert cc.execute() == "done"
    assert seen[0] == {"FAST": "done", "SLOW": None}
    assert seen[-1] == {"FAST": "done", "SLOW": "preempted"}
    assert blocker.saw_preempt


def test_child_termination_cb_false_lets_children_finish() -> None:
    finisher = Fn(
        lambda s, ud: "preempted" if s.preempt_requested() else "done", ["done", "preempted"]
    )
    cc = conc(["done"], child_termination_cb=lambda o: False)
    cc.add("A", Leaf(["done"]))
    cc.add("B", finisher)
    cc.execute()
    assert not finisher.preempt_requested()
    assert cc._child_outcomes == {"A": "done", "B": "done"}


def test_callbacks_start_transition_termination() -> None:
    record: list[tuple[str, object]] = []
    lock = threading.Lock()

    def on_transition(ud: object, active: list[str], tag: str) -> None:
        with lock:
            record.append(("transition", tag))

    cc = conc()
    cc.add("A", Leaf())
    cc.add("B", Leaf())
    cc.register_start_cb(lambda ud, initial: record.append(("start", sorted(initial))))
    cc.register_transition_cb(on_transition, ["t"])
    cc.register_termination_cb(
        lambda ud, terminal, outcome: record.append(("end", (sorted(terminal), outcome)))
    )
    assert cc.execute() == "done"
    assert record[0] == ("start", ["A", "B"])
    assert record[-1] == ("end", (["A", "B"], "done"))
    # Twice per child: when it starts and when it finishes.
    assert record[1:-1] == [("transition", "t")] * 4


def test_active_states_while_running_and_empty_when_idle() -> None:
    gate = threading.Event()
    seen: list[list[str]] = []
    cc = conc()

    def fast(s: Fn, ud: object) -> str:
        gate.set()
        return "done"

    def watcher(s: Fn, ud: object) -> str:
        gate.wait(HANG)
        # FAST may or may not have been recorded yet; WATCH is certainly active.
        seen.append(cc.get_active_states())
        return "done"

    cc.add("FAST", Fn(fast))
    cc.add("WATCH", Fn(watcher))
    assert cc.get_active_states() == []
    cc.execute()
    assert "WATCH" in seen[0]
    assert cc.get_active_states() == []
    assert not cc.is_running()


def test_initial_states_are_all_children() -> None:
    cc = conc()
    cc.add("A", Leaf())
    cc.add("B", Leaf())
    assert cc.get_initial_states() == ["A", "B"]
    assert list(cc.get_children()) == ["A", "B"]


def test_set_initial_state_merges_userdata_and_checks_labels() -> None:
    cc = conc()
    cc.add("A", Leaf())
    ud = smach.UserData()
    ud.x = 1
    cc.set_initial_state(["A"], ud)
    assert cc.userdata.x == 1
    with pytest.raises(smach.InvalidStateError):
        cc.set_initial_state(["NOPE"], ud)


def test_internal_edges_come_from_outcome_map() -> None:
    cc = conc(outcome_map={"failed": {"A": ["x", "y"]}})
    cc.add("A", Leaf(["x", "y"]))
    assert sorted(cc.get_internal_edges()) == [("x", "A", "failed"), ("y", "A", "failed")]


def test_outcome_map_names_unknown_child_fails_at_close() -> None:
    cc = conc(outcome_map={"failed": {"GHOST": "x"}})
    with pytest.raises(smach.InvalidTransitionError) as info, cc:
        smach.Concurrence.add("A", Leaf(["x"]))
    assert "GHOST" in str(info.value)


def test_outcome_map_names_unregistered_child_outcome_fails_at_close() -> None:
    cc = conc(outcome_map={"failed": {"A": "nope"}})
    with pytest.raises(smach.InvalidTransitionError) as info, cc:
        smach.Concurrence.add("A", Leaf(["x"]))
    assert "nope" in str(info.value)
    assert "A" in str(info.value)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"default_outcome": None},
        {"default_outcome": "not_an_outcome"},
        {"default_outcome": 3},
        {"default_outcome": "done", "outcome_map": {"unknown": {"A": "x"}}},
        {"default_outcome": "done", "outcome_cb": "not callable"},
        {"default_outcome": "done", "child_termination_cb": 5},
    ],
)
def test_constructor_rejects_bad_policy(kwargs: dict[str, object]) -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.Concurrence(["done"], **kwargs)  # type: ignore[arg-type]


def test_concurrence_userdata_writes_are_visible_to_other_children() -> None:
    written = threading.Event()

    def writer(s: Fn, ud: object) -> str:
        ud.shared = 1  # type: ignore[attr-defined]
        written.set()
        return "done"

    def reader(s: Fn, ud: object) -> str:
        written.wait(HANG)
        return "done" if ud.shared == 1 else "failed"  # type: ignore[attr-defined]

    cc = conc(outcome_map={"failed": {"R": "failed"}})
    cc.add("W", Fn(writer, output_keys=["shared"]))
    cc.add("R", Fn(reader, ["done", "failed"], input_keys=["shared"]))
    assert cc.execute() == "done"
