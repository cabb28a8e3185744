"""Preemption scenarios: trees preempted from another thread at different moments.

No timing thresholds: blocked states wait on ``preempt_event`` with a generous
timeout (``HANG``) and report ``'timeout'`` if a preempt was lost.
"""

from __future__ import annotations

import threading
import time

import pytest
from smach_helpers import (
    HANG,
    Blocker,
    Fn,
    Leaf,
    LogRecorder,
    PreemptAtStart,
    all_flags,
    join,
    preempt_when,
    start_thread,
)

import smach

pytestmark = pytest.mark.timeout(10)

OUTCOMES = ["done", "preempted", "timeout"]


def assert_clean(root: smach.State) -> None:
    flags = all_flags(root)
    assert not any(flags.values()), f"preempt flags left set: {flags}"


def sm_of(state: smach.State, outcomes: list[str] | None = None) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes or OUTCOMES)
    sm.add("S", state)
    return sm


def conc_of(*states: smach.State, **kwargs: object) -> smach.Concurrence:
    # A lost preempt shows up as the 'timeout' outcome of the first child.
    cc = smach.Concurrence(OUTCOMES, "done", outcome_map={"timeout": {"C0": "timeout"}}, **kwargs)
    for i, state in enumerate(states):
        cc.add(f"C{i}", state)
    return cc


# -- StateMachine ---------------------------------------------------------------------------


def test_preempt_before_execute_preempts_the_initial_state() -> None:
    first = PreemptAtStart()
    second = Leaf(["done"])
    sm = smach.StateMachine(OUTCOMES)
    sm.add("A", first, {"done": "B"})
    sm.add("B", second)
    join(start_thread(sm.request_preempt))
    assert sm.execute() == "preempted"
    assert first.saw_preempt
    assert second.calls == 0
    assert_clean(sm)


def test_preempt_during_a_child_reaches_the_running_child() -> None:
    blocker = Blocker()
    sm = sm_of(blocker)
    thread = preempt_when(blocker.started, sm)
    assert sm.execute() == "preempted"
    join(thread)
    assert blocker.saw_preempt
    assert_clean(sm)


def test_a_preempt_reaches_the_running_child_once() -> None:
    from smach.introspection.events import PreemptRequested

    blocker = Blocker()
    sm = sm_of(blocker)
    seen: list[str] = []
    sm.add_listener(lambda e: seen.append(e.path) if isinstance(e, PreemptRequested) else None)
    thread = preempt_when(blocker.started, sm)
    assert sm.execute() == "preempted"
    join(thread)
    assert sorted(seen) == ["/ROOT", "/ROOT/S"]  # one request each, none twice


def test_state_blocked_on_preempt_event_returns_preempted() -> None:
    class WaitsOnEvent(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["preempted", "timeout"])
            self.waiting = threading.Event()

        def execute(self, ud: object) -> str:
            self.waiting.set()
            if self.preempt_event.wait(HANG):
                self.service_preempt()
                return "preempted"
            return "timeout"

    state = WaitsOnEvent()
    thread = preempt_when(state.waiting, state)
    assert state.execute(smach.UserData()) == "preempted"
    join(thread)
    assert not state.preempt_requested()
    assert not state.preempt_event.is_set()


def test_state_sleeping_returns_at_once_on_preempt() -> None:
    started = threading.Event()

    def body(s: Fn, ud: object) -> str:
        started.set()
        if s.sleep(60):
            s.service_preempt()
            return "preempted"
        return "done"

    sm = sm_of(Fn(body, ["done", "preempted"]))
    thread = preempt_when(started, sm)
    t0 = time.monotonic()
    assert sm.execute() == "preempted"
    assert time.monotonic() - t0 < HANG
    join(thread)


def test_unserviced_preempt_flows_to_the_next_state() -> None:
    started = threading.Event()
    sent = threading.Event()

    def ignores(s: Fn, ud: object) -> str:
        started.set()
        sent.wait(HANG)
        return "next"

    nxt = PreemptAtStart()
    sm = smach.StateMachine(OUTCOMES)
    sm.add("A", Fn(ignores, ["next"]), {"next": "B"})
    sm.add("B", nxt)

    def preempt() -> None:
        started.wait(HANG)
        sm.request_preempt()
        sent.set()

    thread = start_thread(preempt)
    assert sm.execute() == "preempted"
    join(thread)
    assert nxt.saw_preempt
    assert_clean(sm)


def test_preempt_between_states_hits_the_next_state() -> None:
    nxt = PreemptAtStart()
    sm = smach.StateMachine(OUTCOMES)
    sm.add("A", Leaf(["next"]), {"next": "B"})
    sm.add("B", nxt)
    # Transition callbacks run between two states, in the executing thread.
    sm.register_transition_cb(lambda ud, active: join(start_thread(sm.request_preempt)))
    assert sm.execute() == "preempted"
    assert nxt.saw_preempt
    assert_clean(sm)


def test_serviced_preempt_is_just_an_outcome_and_the_machine_goes_on() -> None:
    blocker = Blocker()
    recover = PreemptAtStart()
    sm = smach.StateMachine(OUTCOMES)
    sm.add("WORK", blocker, {"preempted": "RECOVER"})
    sm.add("RECOVER", recover)
    thread = preempt_when(blocker.started, sm)
    assert sm.execute() == "done"
    join(thread)
    assert recover.calls == 1
    assert not recover.saw_preempt
    assert_clean(sm)


def test_recall_preempt_withdraws_a_pending_request() -> None:
    first = PreemptAtStart()
    sm = sm_of(first)
    sm.request_preempt()
    sm.recall_preempt()
    assert sm.execute() == "done"
    assert not first.saw_preempt


def test_nested_statemachine_child_is_preempted() -> None:
    blocker = Blocker()
    inner = smach.StateMachine(OUTCOMES)
    inner.add("BLOCK", blocker)
    outer = sm_of(inner)
    thread = preempt_when(blocker.started, outer)
    assert outer.execute() == "preempted"
    join(thread)
    assert blocker.saw_preempt
    assert_clean(outer)


def test_serviced_nested_preempt_lets_the_parent_continue() -> None:
    blocker = Blocker()
    inner = smach.StateMachine(OUTCOMES)
    inner.add("BLOCK", blocker)
    recover = PreemptAtStart()
    outer = smach.StateMachine(OUTCOMES)
    outer.add("SUB", inner, {"preempted": "RECOVER"})
    outer.add("RECOVER", recover)
    thread = preempt_when(blocker.started, outer)
    assert outer.execute() == "done"
    join(thread)
    assert recover.calls == 1
    assert not recover.saw_preempt


def test_preempting_an_inner_container_leaves_the_parent_running() -> None:
    blocker = Blocker()
    inner = smach.StateMachine(OUTCOMES)
    inner.add("BLOCK", blocker)
    after = PreemptAtStart()
    outer = smach.StateMachine(OUTCOMES)
    outer.add("SUB", inner, {"preempted": "AFTER"})
    outer.add("AFTER", after)
    thread = preempt_when(blocker.started, inner)
    assert outer.execute() == "done"
    join(thread)
    assert after.calls == 1
    assert not after.saw_preempt
    assert not outer.preempt_requested()


# -- Concurrence --------------------------------------------------------------------------------


def test_preempt_reaches_every_running_child_of_a_concurrence() -> None:
    a, b = Blocker(), Blocker()
    cc = conc_of(a, b)
    sm = sm_of(cc)
    both = threading.Event()
    watcher = start_thread(lambda: a.started.wait(HANG) and b.started.wait(HANG) and both.set())
    thread = preempt_when(both, sm)
    assert sm.execute() == "preempted"
    join(watcher, thread)
    assert a.saw_preempt
    assert b.saw_preempt
    assert_clean(sm)


def test_concurrence_preempted_before_execute_preempts_children() -> None:
    a, b = Blocker(), Blocker()
    cc = conc_of(a, b)
    join(start_thread(cc.request_preempt))
    assert cc.execute() == "preempted"
    assert a.saw_preempt
    assert b.saw_preempt
    assert_clean(cc)


def test_concurrence_without_preempted_outcome_applies_its_policy() -> None:
    blocker = Blocker()
    cc = smach.Concurrence(["done", "stopped"], "done", outcome_map={"stopped": {"B": "preempted"}})
    cc.add("B", blocker)
    thread = preempt_when(blocker.started, cc)
    assert cc.execute() == "stopped"
    join(thread)
    assert_clean(cc)


def test_concurrence_with_unserviced_child_does_not_return_preempted(logs: LogRecorder) -> None:
    started = threading.Event()

    def stubborn(s: Fn, ud: object) -> str:
        started.set()
        s.preempt_event.wait(HANG)
        return "done"  # noticed, but does not service

    cc = smach.Concurrence(OUTCOMES, "done")
    cc.add("S", Fn(stubborn, ["done"]))
    thread = preempt_when(started, cc)
    assert cc.execute() == "done"
    join(thread)
    assert any("S" in m for m in logs.warn)
    assert_clean(cc)


def test_child_termination_preemption_is_not_a_container_preempt() -> None:
    blocker = Blocker()
    cc = smach.Concurrence(
        OUTCOMES, "done", child_termination_cb=lambda outcomes: outcomes["FAST"] is not None
    )
    cc.add("FAST", Leaf(["done"]))
    cc.add("SLOW", blocker)
    assert cc.execute() == "done"
    assert blocker.saw_preempt
    assert_clean(cc)


def test_preempt_inside_nested_concurrences_reaches_every_leaf() -> None:
    leaves = [Blocker() for _ in range(3)]
    inner = smach.Concurrence(OUTCOMES, "done")
    inner.add("L0", leaves[0])
    inner.add("L1", leaves[1])
    outer = smach.Concurrence(OUTCOMES, "done")
    outer.add("INNER", inner)
    outer.add("L2", leaves[2])
    sm = sm_of(outer)
    all_started = threading.Event()
    watcher = start_thread(
        lambda: all(leaf.started.wait(HANG) for leaf in leaves) and all_started.set()
    )
    thread = preempt_when(all_started, sm)
    assert sm.execute() == "preempted"
    join(watcher, thread)
    assert all(leaf.saw_preempt for leaf in leaves)
    assert_clean(sm)


def test_preempt_reaches_statemachine_inside_concurrence_inside_statemachine() -> None:
    blocker = Blocker()
    inner_sm = smach.StateMachine(OUTCOMES)
    inner_sm.add("DEEP", blocker)
    cc = smach.Concurrence(OUTCOMES, "done")
    cc.add("SM", inner_sm)
    # Services a preempt if one arrives before it starts (it may start after the request).
    cc.add("OTHER", PreemptAtStart())
    root = sm_of(cc)
    thread = preempt_when(blocker.started, root)
    assert root.execute() == "preempted"
    join(thread)
    assert blocker.saw_preempt
    assert_clean(root)


# -- Iterator -------------------------------------------------------------------------------------


def test_preempt_during_an_item_stops_the_iterator() -> None:
    blocker = Blocker()
    body = smach.StateMachine(["continue", "preempted", "timeout"])
    body.add("BLOCK", blocker, {"timeout": "continue"})
    it = smach.Iterator(["preempted", "timeout"], [], [], it=range(5), exhausted_outcome="done")
    it.set_contained_state("BODY", body, loop_outcomes=["continue"])
    root = smach.StateMachine(["done", "preempted", "timeout"])
    root.add("IT", it)
    thread = preempt_when(blocker.started, root)
    assert root.execute() == "preempted"
    join(thread)
    assert blocker.calls == 1
    assert_clean(root)


def test_preempt_between_items_hits_the_next_item() -> None:
    calls: list[bool] = []

    def body(s: Fn, ud: object) -> str:
        calls.append(s.preempt_requested())
        if s.preempt_requested():
            s.service_preempt()
            return "preempted"
        return "continue"

    it = smach.Iterator(["preempted"], [], [], it=range(5), exhausted_outcome="done")
    it.set_contained_state("BODY", Fn(body, ["continue", "preempted"]), loop_outcomes=["continue"])
    # Transition callbacks run between two items, in the executing thread.
    it.register_transition_cb(lambda ud, active: join(start_thread(it.request_preempt)))
    assert it.execute() == "preempted"
    assert calls == [False, True]
    assert_clean(it)


# -- no lost preempts, clean flags ----------------------------------------------------------------


def _race(target: smach.State, runs: int = 25) -> list[str | None]:
    outcomes = []
    for _ in range(runs):
        thread = start_thread(target.request_preempt)
        outcomes.append(target.execute())
        join(thread)
        assert_clean(target)
    return outcomes


def test_no_lost_preempt_racing_statemachine_start() -> None:
    assert set(_race(sm_of(Blocker()))) == {"preempted"}


def test_no_lost_preempt_racing_concurrence_start() -> None:
    assert set(_race(conc_of(Blocker(), Blocker()))) == {"preempted"}


def test_no_lost_preempt_racing_nested_tree_start() -> None:
    inner = smach.StateMachine(OUTCOMES)
    inner.add("B", Blocker())
    cc = smach.Concurrence(OUTCOMES, "done", outcome_map={"timeout": {"SM": "timeout"}})
    cc.add("SM", inner)
    cc.add("B2", Blocker())
    assert set(_race(sm_of(cc))) == {"preempted"}


def test_unserviced_flags_are_cleared_after_a_top_level_run() -> None:
    started = threading.Event()

    def ignores(s: Fn, ud: object) -> str:
        started.set()
        s.preempt_event.wait(HANG)
        return "done"

    inner = smach.StateMachine(OUTCOMES)
    inner.add("IGNORE", Fn(ignores, ["done"]))
    root = sm_of(inner)
    thread = preempt_when(started, root)
    assert root.execute() == "done"
    join(thread)
    assert_clean(root)


def test_leftover_flags_do_not_leak_into_the_next_execution() -> None:
    started = threading.Event()
    runs: list[bool] = []

    def body(s: Fn, ud: object) -> str:
        runs.append(s.preempt_requested())
        if len(runs) == 1:
            started.set()
            s.preempt_event.wait(HANG)
        return "done"  # never services

    sm = sm_of(Fn(body, ["done"]))
    thread = preempt_when(started, sm)
    assert sm.execute() == "done"
    join(thread)
    assert sm.execute() == "done"
    assert runs == [False, False]


def test_flags_are_clean_after_a_run_that_raised() -> None:
    started = threading.Event()

    def fails(s: Fn, ud: object) -> str:
        started.set()
        s.preempt_event.wait(HANG)
        raise RuntimeError("failed while preempted")

    cc = smach.Concurrence(OUTCOMES, "done")
    cc.add("F", Fn(fails, ["done"]))
    cc.add("B", Blocker())
    root = sm_of(cc)
    thread = preempt_when(started, root)
    with pytest.raises(smach.InvalidUserCodeError):
        root.execute()
    join(thread)
    assert_clean(root)
    assert not root.is_running()
    assert not cc.is_running()


def test_request_preempt_returns_at_once_while_child_ignores_it() -> None:
    started = threading.Event()
    release = threading.Event()
    returned = threading.Event()

    def busy(s: Fn, ud: object) -> str:
        started.set()
        release.wait(HANG)
        return "done"

    sm = sm_of(Fn(busy, ["done"]))

    def preempt() -> None:
        started.wait(HANG)
        sm.request_preempt()
        returned.set()
        release.set()

    thread = start_thread(preempt)
    assert sm.execute() == "done"
    join(thread)
    assert returned.is_set()


def test_preempted_iterator_whose_child_ignores_the_request_does_not_crash() -> None:
    # The first item ignores the preempt and returns a loop outcome. Either the request
    # flows on to the next item (as in a StateMachine) or the loop stops; it must not turn
    # into an InvalidUserCodeError because 'continue' is not an Iterator outcome.
    calls: list[bool] = []
    it = smach.Iterator(["preempted"], [], [], it=range(5), exhausted_outcome="done")

    def body(s: Fn, ud: object) -> str:
        if not calls:
            join(start_thread(it.request_preempt))
        calls.append(s.preempt_requested())
        if len(calls) > 1 and s.preempt_requested():
            s.service_preempt()
            return "preempted"
        return "continue"

    it.set_contained_state("BODY", Fn(body, ["continue", "preempted"]), loop_outcomes=["continue"])
    outcome = it.execute()
    assert outcome in it.get_registered_outcomes()
    assert len(calls) <= 2
    assert_clean(it)
