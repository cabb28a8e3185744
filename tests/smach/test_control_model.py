"""The control model alone: the Controller driven through its hooks, as a container would."""

from __future__ import annotations

import threading

import pytest

import smach
from smach.control import CONTROL_STATES, ControlError, Controller, ControlRecord, controller_of
from smach.testing import ScriptedState

pytestmark = pytest.mark.timeout(30)


def _tree() -> tuple[smach.StateMachine, smach.State, smach.State]:
    sm = smach.StateMachine(outcomes=["done"])
    a = ScriptedState(["next"], outcomes=["next", "other", "preempted"])
    b = ScriptedState(["done"], outcomes=["done", "preempted"])
    sm.add("A", a, transitions={"next": "B", "other": "B", "preempted": "done"})
    sm.add("B", b, transitions={"preempted": "done"})
    return sm, a, b


def _enter_in_thread(
    ctl: Controller, container: smach.State, path: str, state: smach.State
) -> tuple[threading.Thread, threading.Event]:
    entered = threading.Event()

    def run() -> None:
        ctl.enter(container, path, state)
        entered.set()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, entered


def test_a_new_controller_is_running_and_attached_to_the_tree() -> None:
    sm, _, _ = _tree()
    with Controller(sm) as ctl:
        assert controller_of(sm) is ctl
        assert ctl.status().state == "running"
        assert ctl.status().describe() == "running"
    assert controller_of(sm) is None


def test_a_tree_takes_one_controller_and_only_containers_are_controlled() -> None:
    sm, a, _ = _tree()
    with Controller(sm), pytest.raises(ControlError, match="already has a controller"):
        Controller(sm)
    with pytest.raises(ControlError, match="needs a smach container"):
        Controller(a)  # type: ignore[arg-type]


def test_pause_holds_the_next_state_before_it_starts_and_resume_lets_it_go() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    assert ctl.pause().state == "pausing"
    thread, entered = _enter_in_thread(ctl, sm, "/ROOT/A", a)
    assert ctl.wait_for("paused", timeout=5)
    assert ctl.status().held == ("/ROOT/A",)
    assert ctl.status().describe() == "paused before /ROOT/A"
    assert not entered.is_set()
    ctl.resume()
    thread.join(5)
    assert entered.is_set()
    assert ctl.status().running == ("/ROOT/A",)


def test_step_lets_exactly_the_longest_held_state_start() -> None:
    sm, a, b = _tree()
    ctl = Controller(sm)
    ctl.pause()
    t1, e1 = _enter_in_thread(ctl, sm, "/ROOT/A", a)
    assert ctl.wait_for("paused", timeout=5)
    t2, e2 = _enter_in_thread(ctl, sm, "/ROOT/B", b)
    with ctl._cond:
        assert ctl._cond.wait_for(lambda: len(ctl.status().held) == 2, 5)
    ctl.step()
    t1.join(5)
    assert e1.is_set() and not e2.is_set()
    assert ctl.status().state == "paused"
    assert ctl.status().held == ("/ROOT/B",)
    ctl.resume()
    t2.join(5)
    assert e2.is_set()


def test_step_while_running_lets_the_next_state_start_then_holds_the_one_after() -> None:
    sm, a, b = _tree()
    ctl = Controller(sm)
    ctl.step()
    ctl.enter(sm, "/ROOT/A", a)  # uses the step: does not block
    assert ctl.status().steps == 0
    thread, entered = _enter_in_thread(ctl, sm, "/ROOT/B", b)
    assert ctl.wait_for("paused", timeout=5)
    assert not entered.is_set()
    ctl.resume()
    thread.join(5)


@pytest.mark.parametrize(
    ("pattern", "path"),
    [
        ("/ROOT/B", "/ROOT/B"),
        ("*/B", "/ROOT/B"),
        ("/ROOT/*", "/ROOT/B"),
        ("/ROOT/*/PICK", "/ROOT/FETCH/PICK"),
    ],
)
def test_a_breakpoint_pauses_before_a_matching_path(pattern: str, path: str) -> None:
    sm, _, b = _tree()
    ctl = Controller(sm)
    records: list[ControlRecord] = []
    ctl.add_observer(records.append)
    ctl.add_breakpoint(pattern)
    thread, entered = _enter_in_thread(ctl, sm, path, b)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    status = ctl.status()
    assert status.breakpoint == path
    assert status.describe() == f"at breakpoint {path}"
    assert not entered.is_set()
    ctl.resume()
    thread.join(5)
    assert entered.is_set()
    assert [r.action for r in records] == ["add_breakpoint", "breakpoint_hit", "resume"]
    assert records[1].source == "machine" and records[1].details["pattern"] == pattern


def test_a_state_not_matching_any_breakpoint_is_not_held() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.add_breakpoint("/ROOT/B")
    ctl.enter(sm, "/ROOT/A", a)
    assert ctl.status().state == "running"


@pytest.mark.parametrize("bad", ["", "PICK", 3, "/" + "x" * 600])
def test_a_malformed_breakpoint_is_refused_with_what_is_allowed(bad: object) -> None:
    sm, _, _ = _tree()
    ctl = Controller(sm)
    with pytest.raises(ControlError, match="breakpoint"):
        ctl.add_breakpoint(bad)  # type: ignore[arg-type]


def test_toggle_and_remove_breakpoints() -> None:
    sm, _, _ = _tree()
    ctl = Controller(sm)
    assert ctl.toggle_breakpoint("/ROOT/A").breakpoints == ("/ROOT/A",)
    assert ctl.toggle_breakpoint("/ROOT/A").breakpoints == ()
    with pytest.raises(ControlError, match=r"no breakpoint '/ROOT/A'; breakpoints: none"):
        ctl.remove_breakpoint("/ROOT/A")
    ctl.add_breakpoint("/ROOT/A")
    ctl.add_breakpoint("*/B")
    assert ctl.clear_breakpoints().breakpoints == ()


def test_a_preempt_releases_a_held_state() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.pause()
    thread, entered = _enter_in_thread(ctl, sm, "/ROOT/A", a)
    assert ctl.wait_for("paused", timeout=5)
    a.request_preempt()  # an ordinary request, not through the controller
    thread.join(5)
    assert entered.is_set() and a.preempt_requested()


def test_force_outcome_takes_the_given_outcome_when_the_state_returns() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.enter(sm, "/ROOT/A", a)
    status = ctl.force_outcome("other")
    assert status.forced == {"/ROOT/A": "other"}
    assert a.preempt_requested()
    assert ctl.leave("/ROOT/A", a, "preempted") == "other"
    assert not a.preempt_requested()  # the means of the force does not flow on
    assert ctl.history[-1].action == "outcome_forced"
    assert ctl.history[-1].details == {"outcome": "other", "returned": "preempted"}


def test_force_outcome_refuses_unknown_outcomes_and_states_not_running() -> None:
    sm, a, b = _tree()
    ctl = Controller(sm)
    with pytest.raises(ControlError, match="no state is running"):
        ctl.force_outcome("next")
    ctl.enter(sm, "/ROOT/A", a)
    with pytest.raises(ControlError, match=r"/ROOT/A has no outcome 'done'; its outcomes: next"):
        ctl.force_outcome("done")
    with pytest.raises(ControlError, match=r"/ROOT/B is not running .* running: /ROOT/A"):
        ctl.force_outcome("done", "/ROOT/B")
    ctl.enter(sm, "/ROOT/B", b)
    with pytest.raises(ControlError, match="2 states are running"):
        ctl.force_outcome("done")
    assert not a.preempt_requested() and not b.preempt_requested()


def test_a_force_that_missed_its_run_does_not_hit_the_next_run_of_the_path() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.enter(sm, "/ROOT/A", a)
    ctl.force_outcome("other")
    a.recall_preempt()
    ctl._running.clear()  # the run ended without leave() (it raised)
    ctl.enter(sm, "/ROOT/A", a)
    assert ctl.leave("/ROOT/A", a, "next") == "next"


def test_force_outcome_and_the_state_returning_race_to_one_consistent_answer() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    for _ in range(300):
        ctl.enter(sm, "/ROOT/A", a)
        answers: list[str | None] = []
        errors: list[ControlError] = []
        go = threading.Barrier(2)

        def leave(go: threading.Barrier = go, answers: list[str | None] = answers) -> None:
            go.wait()
            answers.append(ctl.leave("/ROOT/A", a, "next"))

        def force(go: threading.Barrier = go, errors: list[ControlError] = errors) -> None:
            go.wait()
            try:
                ctl.force_outcome("other")
            except ControlError as exc:
                errors.append(exc)

        threads = [threading.Thread(target=leave), threading.Thread(target=force)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(5)
        # Either the force came first (taken, flag cleared) or it was refused.
        assert answers == (["next"] if errors else ["other"])
        assert not a.preempt_requested()
        assert ctl.status().forced == {} and ctl.status().running == ()


def test_preempt_by_path_reaches_that_state_and_bad_paths_are_named() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.preempt("/ROOT/A", source="cli")
    assert a.preempt_requested() and not sm.preempt_requested()
    assert ctl.history[-1].source == "cli" and ctl.history[-1].path == "/ROOT/A"
    with pytest.raises(ControlError, match=r"/ROOT has no child 'C'; children: A, B"):
        ctl.preempt("/ROOT/C")
    with pytest.raises(ControlError, match="starts with '/'"):
        ctl.preempt("ROOT")
    with pytest.raises(ControlError, match="not in this tree"):
        ctl.preempt("/OTHER/A")
    ctl.preempt()
    assert sm.preempt_requested()


def test_concurrent_requests_leave_a_consistent_state() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    go = threading.Barrier(6)

    def hammer(action: str) -> None:
        go.wait()
        for i in range(200):
            if action == "pause":
                ctl.pause()
            elif action == "resume":
                ctl.resume()
            elif action == "step":
                ctl.step()
            elif action == "bp":
                ctl.toggle_breakpoint(f"/ROOT/X{i % 3}")
            elif action == "status":
                assert ctl.status().state in CONTROL_STATES
            else:
                ctl.enter(sm, "/ROOT/A", a)
                ctl.leave("/ROOT/A", a, "next")

    threads = [
        threading.Thread(target=hammer, args=(kind,), daemon=True)
        for kind in ("pause", "resume", "step", "bp", "status", "run")
    ]
    for t in threads:
        t.start()
    # The running thread may be held by the last pause: let it finish.
    for _ in range(100):
        ctl.resume()
        if not threads[-1].is_alive() and all(not t.is_alive() for t in threads):
            break
        threads[-1].join(0.05)
    for t in threads:
        t.join(5)
        assert not t.is_alive()
    ctl.resume()
    assert ctl.status().state == "running" and ctl.status().held == ()
    assert 0 < len(ctl.history) <= 1000
    assert all(r.state in CONTROL_STATES for r in ctl.history)


def test_close_releases_held_states_and_detaches() -> None:
    sm, a, _ = _tree()
    ctl = Controller(sm)
    ctl.pause()
    thread, entered = _enter_in_thread(ctl, sm, "/ROOT/A", a)
    assert ctl.wait_for("paused", timeout=5)
    ctl.close()
    thread.join(5)
    assert entered.is_set() and controller_of(sm) is None


def test_a_failing_observer_is_removed_and_the_request_still_succeeds(logs: object) -> None:
    sm, _, _ = _tree()
    ctl = Controller(sm)

    def broken(record: ControlRecord) -> None:
        raise RuntimeError("observer down")

    ctl.add_observer(broken)
    assert ctl.pause().state == "pausing"
    assert ctl._observers == ()


def test_records_say_what_from_where_and_when() -> None:
    sm, _, _ = _tree()
    ctl = Controller(sm)
    ctl.pause(source="viewer")
    record = ctl.history[-1]
    data = record.to_json()
    assert data["action"] == "pause" and data["source"] == "viewer"
    assert data["time"] > 0 and data["wall"] > 1e9 and data["state"] == "pausing"
    with pytest.raises(ControlError, match="control source"):
        ctl.resume(source="")
    with pytest.raises(ControlError, match="unknown control state"):
        ctl.wait_for("sleeping", timeout=0)  # type: ignore[arg-type]
