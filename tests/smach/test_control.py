"""Runtime control of running trees: every control in every container, and the races."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from smach_helpers import Runner

import smach
from smach.control import ControlError, Controller
from smach.testing import BlockingState, EventRecorder, ScriptedState

pytestmark = pytest.mark.timeout(60)


def _chain(*labels: str) -> tuple[smach.StateMachine, dict[str, ScriptedState]]:
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    states: dict[str, ScriptedState] = {}
    for i, label in enumerate(labels):
        nxt = labels[i + 1] if i + 1 < len(labels) else "done"
        # (a short preempt-aware delay: a preempted state returns "preempted")
        states[label] = ScriptedState(["ok"], outcomes=["ok", "preempted"], delay=0.001)
        sm.add(label, states[label], transitions={"ok": nxt, "preempted": "preempted"})
    return sm, states


def _until(predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.002)
    return True


def _entered(recorder: EventRecorder) -> list[str]:
    return [e.path for e in recorder.of_kind("state_entered")]


# -- StateMachine ---------------------------------------------------------------------------
def test_an_uncontrolled_machine_runs_as_before() -> None:
    sm, states = _chain("A", "B")
    assert sm.execute() == "done"
    assert all(s.call_count == 1 for s in states.values())


def test_pause_before_a_run_holds_the_first_state_until_resume() -> None:
    sm, states = _chain("A", "B")
    ctl = Controller(sm)
    ctl.pause()
    run = Runner(sm)
    assert ctl.wait_for("paused", timeout=5)
    assert ctl.status().held == ("/ROOT/A",) and states["A"].call_count == 0
    ctl.resume()
    assert run.result() == "done"


def test_pause_takes_effect_at_the_next_transition_without_interrupting_the_state() -> None:
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    work = BlockingState(outcomes=("ok", "preempted"))
    after = ScriptedState(["ok"], outcomes=["ok"])
    sm.add("WORK", work, transitions={"ok": "AFTER", "preempted": "preempted"})
    sm.add("AFTER", after, transitions={"ok": "done"})
    ctl = Controller(sm)
    run = Runner(sm)
    assert work.started.wait(5)
    assert ctl.pause().state == "pausing"
    assert ctl.status().describe() == "pausing (waiting for /ROOT/WORK to return)"
    work.release("ok")  # the running state finishes normally ...
    assert ctl.wait_for("paused", timeout=5)  # ... and the next one is held
    assert ctl.status().held == ("/ROOT/AFTER",) and after.call_count == 0
    assert not work.preempt_requested()
    ctl.resume()
    assert run.result() == "done" and after.call_count == 1


def test_step_runs_one_state_at_a_time() -> None:
    sm, _ = _chain("A", "B", "C")
    recorder = EventRecorder()
    sm.add_listener(recorder)
    ctl = Controller(sm)
    ctl.pause()
    run = Runner(sm)
    for expected in ("/ROOT/A", "/ROOT/B", "/ROOT/C"):
        assert ctl.wait_for("paused", timeout=5)
        assert ctl.status().held == (expected,)
        ctl.step()
        recorder.wait_for(lambda e, p=expected: e.kind == "state_exited" and e.path == p)
    assert run.result() == "done"
    assert _entered(recorder) == ["/ROOT/A", "/ROOT/B", "/ROOT/C"]


def test_a_breakpoint_holds_before_entering_and_the_transition_is_already_reported() -> None:
    sm, states = _chain("A", "B", "C")
    recorder = EventRecorder()
    sm.add_listener(recorder)
    ctl = Controller(sm)
    ctl.add_breakpoint("/ROOT/B")
    run = Runner(sm)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    assert ctl.status().describe() == "at breakpoint /ROOT/B"
    assert states["A"].call_count == 1 and states["B"].call_count == 0
    recorder.wait_for(lambda e: e.kind == "transition" and e.target == "B")
    assert "/ROOT/B" not in _entered(recorder)
    ctl.resume()
    assert run.result() == "done"


def test_a_glob_breakpoint_matches_nested_states() -> None:
    inner, _ = _chain("PICK", "PLACE")
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    sm.add("FETCH", inner, transitions={"done": "done", "preempted": "preempted"})
    ctl = Controller(sm)
    ctl.add_breakpoint("*/PLACE")
    run = Runner(sm)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    assert ctl.status().breakpoint == "/ROOT/FETCH/PLACE"
    ctl.resume()
    assert run.result() == "done"


def test_force_outcome_of_the_active_leaf_takes_that_transition() -> None:
    sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    grasp = BlockingState(outcomes=("grasped", "missed", "preempted"))
    sm.add("GRASP", grasp, transitions={"grasped": "done", "missed": "failed"})
    ctl = Controller(sm)
    run = Runner(sm)
    assert grasp.started.wait(5)
    ctl.force_outcome("grasped", source="cli")  # a person finished the grasp by hand
    assert run.result() == "done"
    assert not grasp.preempt_requested() and not sm.preempt_requested()
    assert [r.action for r in ctl.history] == ["force_outcome", "outcome_forced"]
    assert ctl.history[-1].details == {"outcome": "grasped", "returned": "preempted"}


def test_force_outcome_of_a_nested_container_replaces_its_outcome() -> None:
    inner = smach.StateMachine(outcomes=["ok", "preempted"])
    wait = BlockingState(outcomes=("ok", "preempted"))
    inner.add("WAIT", wait)
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    sm.add("INNER", inner, transitions={"ok": "done"})
    ctl = Controller(sm)
    run = Runner(sm)
    assert wait.started.wait(5)
    ctl.force_outcome("ok", "/ROOT/INNER")
    assert run.result() == "done"


def test_force_outcome_while_the_state_returns_takes_one_outcome_and_leaves_no_flag() -> None:
    for attempt in range(40):
        sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
        grasp = BlockingState(outcomes=("grasped", "missed", "preempted"), service=False)
        nxt = ScriptedState(["ok"], outcomes=["ok", "preempted"])
        sm.add("GRASP", grasp, transitions={"grasped": "NEXT", "missed": "failed"})
        sm.add("NEXT", nxt, transitions={"ok": "done"})
        ctl = Controller(sm)
        run = Runner(sm)
        assert grasp.started.wait(5)
        go = threading.Barrier(2)
        refused: list[ControlError] = []

        def force(
            go: threading.Barrier = go,
            refused: list[ControlError] = refused,
            ctl: Controller = ctl,
        ) -> None:
            go.wait()
            try:
                ctl.force_outcome("grasped")
            except ControlError as exc:
                refused.append(exc)

        forcer = threading.Thread(target=force)
        forcer.start()
        go.wait()
        grasp.release("missed")
        forcer.join(5)
        outcome = run.result()
        # Either the force landed while GRASP ran (its outcome taken) or it was refused
        # because GRASP had returned: never a preempt leaking into NEXT.
        assert outcome == ("failed" if refused else "done"), attempt
        assert not nxt.calls or not nxt.calls[0].preempt_requested
        assert ctl.status().forced == {} and ctl.status().running == ()


def test_preempt_releases_a_paused_machine_and_it_ends_preempted() -> None:
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    work = BlockingState(outcomes=("ok", "preempted"))
    sm.add("WORK", work, transitions={"ok": "done"})
    ctl = Controller(sm)
    ctl.pause()
    run = Runner(sm)
    assert ctl.wait_for("paused", timeout=5)
    ctl.preempt(source="ros")
    assert run.result() == "preempted"
    assert work.executions == 1  # it started with the request pending and stopped


def test_an_ordinary_request_preempt_also_releases_a_held_state() -> None:
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "B"})
    sm.add("B", BlockingState(outcomes=("ok", "preempted")), transitions={"ok": "done"})
    ctl = Controller(sm)
    ctl.add_breakpoint("/ROOT/B")
    run = Runner(sm)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    sm.request_preempt()
    assert run.result() == "preempted"


def test_a_controller_survives_between_runs_and_a_closed_one_costs_nothing() -> None:
    sm, states = _chain("A", "B")
    ctl = Controller(sm)
    ctl.add_breakpoint("/ROOT/A")
    for _ in range(2):
        run = Runner(sm)
        assert ctl.wait_for("at_breakpoint", timeout=5)
        ctl.resume()
        assert run.result() == "done"
    ctl.close()
    assert sm.execute() == "done"
    assert states["A"].call_count == 3


def test_an_error_in_a_state_leaves_nothing_running_in_the_controller() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("BAD", smach.CBState(lambda ud: 1 / 0, outcomes=["done"]))
    ctl = Controller(sm)
    with pytest.raises(smach.InvalidUserCodeError):
        sm.execute()
    assert ctl.status().running == ()


def test_a_controlled_subtree_stays_controlled_when_it_is_adopted() -> None:
    inner, _ = _chain("X", "Y")
    ctl = Controller(inner)
    outer = smach.StateMachine(outcomes=["done", "preempted"])
    outer.add("IN", inner, transitions={"done": "done"})
    ctl.add_breakpoint("/ROOT/IN/Y")
    run = Runner(outer)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    ctl.resume()
    assert run.result() == "done"


# -- Concurrence -------------------------------------------------------------------------------
def _concurrence_of_branches() -> tuple[smach.StateMachine, dict[str, ScriptedState]]:
    cc = smach.Concurrence(
        outcomes=["done", "preempted"],
        default_outcome="done",
        outcome_map={"preempted": {"LEFT": "preempted", "RIGHT": "preempted"}},
    )
    states: dict[str, ScriptedState] = {}
    for side in ("LEFT", "RIGHT"):
        branch, inner = _chain(f"{side}1", f"{side}2")
        states.update(inner)
        cc.add(side, branch)
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    sm.add("CC", cc, transitions={"done": "AFTER", "preempted": "preempted"})
    after = ScriptedState(["ok"], outcomes=["ok"])
    states["AFTER"] = after
    sm.add("AFTER", after, transitions={"ok": "done"})
    return sm, states


def test_pause_holds_every_concurrence_branch_at_its_next_transition() -> None:
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
    firsts: dict[str, BlockingState] = {}
    seconds: dict[str, ScriptedState] = {}
    for side in ("LEFT", "RIGHT"):
        branch = smach.StateMachine(outcomes=["done"])
        firsts[side] = BlockingState(outcomes=("ok", "preempted"))
        seconds[side] = ScriptedState(["ok"], outcomes=["ok"])
        branch.add("FIRST", firsts[side], transitions={"ok": "SECOND", "preempted": "done"})
        branch.add("SECOND", seconds[side], transitions={"ok": "done"})
        cc.add(side, branch)
    ctl = Controller(cc)
    run = Runner(cc)
    assert all(f.started.wait(5) for f in firsts.values())
    ctl.pause()
    for first in firsts.values():
        first.release("ok")
    with ctl._cond:
        assert ctl._cond.wait_for(lambda: len(ctl.status().held) == 2, 5)
    assert set(ctl.status().held) == {"/ROOT/LEFT/SECOND", "/ROOT/RIGHT/SECOND"}
    assert all(s.call_count == 0 for s in seconds.values())
    ctl.step()  # the branch held longest moves on, the other stays held
    with ctl._cond:
        assert ctl._cond.wait_for(lambda: len(ctl.status().held) == 1, 5)
    assert sum(s.call_count for s in seconds.values()) == 1
    ctl.resume()
    assert run.result() == "done"
    assert all(s.call_count == 1 for s in seconds.values())


def test_a_breakpoint_in_one_branch_pauses_the_other_branches_too() -> None:
    sm, states = _concurrence_of_branches()
    ctl = Controller(sm)
    ctl.add_breakpoint("/ROOT/CC/RIGHT/RIGHT2")
    run = Runner(sm)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    assert ctl.status().breakpoint == "/ROOT/CC/RIGHT/RIGHT2"
    ctl.resume()
    assert run.result() == "done"
    assert all(s.call_count == 1 for s in states.values())


def test_a_paused_concurrence_branch_is_released_by_a_preempt() -> None:
    sm, _ = _concurrence_of_branches()
    ctl = Controller(sm)
    ctl.pause()
    run = Runner(sm)
    assert ctl.wait_for("paused", timeout=5)
    ctl.preempt()
    assert run.result() == "preempted"


def test_pause_while_a_concurrence_finishes_holds_the_state_after_it() -> None:
    for attempt in range(30):
        cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
        gates = [BlockingState(outcomes=("ok", "preempted")) for _ in range(3)]
        for i, gate in enumerate(gates):
            cc.add(f"C{i}", gate)
        sm = smach.StateMachine(outcomes=["done"])
        after = ScriptedState(["ok"], outcomes=["ok"])
        sm.add("CC", cc, transitions={"done": "AFTER"})
        sm.add("AFTER", after, transitions={"ok": "done"})
        ctl = Controller(sm)
        run = Runner(sm)
        assert all(g.started.wait(5) for g in gates)
        go = threading.Barrier(2)
        pauser = threading.Thread(target=lambda go=go, ctl=ctl: (go.wait(), ctl.pause()))
        pauser.start()
        go.wait()
        for gate in gates:
            gate.release("ok")
        pauser.join(5)
        while run.thread.is_alive() and not ctl.wait_for("paused", timeout=0.05):
            pass
        if ctl.status().state == "paused":
            # The concurrence finished with its outcome; nothing after it started.
            assert ctl.status().held == ("/ROOT/AFTER",) and after.call_count == 0, attempt
            assert cc.get_active_states() == []
            ctl.resume()
        else:  # the pause came after AFTER had started: the run just finishes
            assert after.call_count == 1, attempt
        assert run.result() == "done"
        ctl.close()


def test_force_outcome_in_a_concurrence_needs_a_path_when_several_leaves_run() -> None:
    cc = smach.Concurrence(
        outcomes=["done", "failed"],
        default_outcome="failed",
        outcome_map={"done": {"A": "ok", "B": "ok"}},
    )
    a = BlockingState(outcomes=("ok", "preempted"))
    b = BlockingState(outcomes=("ok", "preempted"))
    cc.add("A", a)
    cc.add("B", b)
    ctl = Controller(cc)
    run = Runner(cc)
    assert a.started.wait(5) and b.started.wait(5)
    with pytest.raises(ControlError, match="2 states are running"):
        ctl.force_outcome("ok")
    ctl.force_outcome("ok", "/ROOT/A")
    b.release("ok")
    assert run.result() == "done"


# -- Iterator and one-child containers -------------------------------------------------------------
def test_pause_and_step_in_an_iterator_hold_each_item() -> None:
    it = smach.Iterator(
        outcomes=["done", "preempted"],
        input_keys=[],
        output_keys=[],
        it=[1, 2, 3],
        it_label="item",
        exhausted_outcome="done",
    )
    body = ScriptedState(["ok"], outcomes=["ok", "preempted"], input_keys=["item"])
    it.set_contained_state("BODY", body, loop_outcomes=["ok"])
    ctl = Controller(it)
    ctl.pause()
    run = Runner(it)
    for done in range(3):
        assert _until(lambda d=done: body.call_count == d and ctl.status().state == "paused")
        ctl.step()
    assert run.result() == "done"
    assert [c.inputs["item"] for c in body.calls] == [1, 2, 3]


def test_force_outcome_inside_retry_and_a_breakpoint_on_its_child() -> None:
    attempt = BlockingState(outcomes=("succeeded", "aborted", "preempted"))
    retry = smach.Retry.wrap("TRY", attempt, attempts=3)
    ctl = Controller(retry)
    ctl.add_breakpoint("/ROOT/TRY")
    run = Runner(retry)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    ctl.resume()
    assert attempt.started.wait(5)
    ctl.force_outcome("succeeded")
    assert run.result() == "succeeded"


def test_concurrent_requests_during_runs_never_hang_or_lose_the_outcome() -> None:
    sm, _ = _concurrence_of_branches()
    ctl = Controller(sm)
    stop = threading.Event()
    actions: list[Callable[[], object]] = [
        ctl.pause,
        ctl.resume,
        ctl.step,
        lambda: ctl.toggle_breakpoint("*/LEFT2"),
        ctl.status,
    ]

    def hammer(action: Callable[[], object]) -> None:
        while not stop.is_set():
            action()

    threads = [threading.Thread(target=hammer, args=(a,), daemon=True) for a in actions]
    for t in threads:
        t.start()
    outcomes = []
    try:
        for _ in range(20):
            run = Runner(sm)
            while run.thread.is_alive():
                ctl.resume()
                run.thread.join(0.01)
            outcomes.append(run.result())
    finally:
        stop.set()
        for t in threads:
            t.join(5)
    assert outcomes == ["done"] * 20


# -- journal -----------------------------------------------------------------------------------
def test_every_control_action_is_journaled_with_what_where_and_when(tmp_path: Path) -> None:
    from smach.introspection.journal import Journal, read_journal

    sm, _ = _chain("A", "B")
    ctl = Controller(sm)
    path = tmp_path / "run.jsonl"
    with Journal(path, sm) as journal:
        ctl.journal_to(journal)
        ctl.add_breakpoint("/ROOT/B", source="cli")
        run = Runner(sm)
        assert ctl.wait_for("at_breakpoint", timeout=5)
        ctl.resume(source="viewer")
        assert run.result() == "done"
    _, records = read_journal(path)
    control = [r for r in records if r["kind"] == "control"]
    assert [(r["action"], r["source"], r["path"]) for r in control] == [
        ("add_breakpoint", "cli", "/ROOT/B"),
        ("breakpoint_hit", "machine", "/ROOT/B"),
        ("resume", "viewer", ""),
    ]
    assert control[1]["state"] == "at_breakpoint"
    # Placed among the events by their monotonic time: the hit comes after A exited.
    exited_a = next(r for r in records if r["kind"] == "state_exited" and r["path"] == "/ROOT/A")
    assert exited_a["time"] <= control[1]["time"] <= control[2]["time"]
    assert all(isinstance(r["wall"], float) and r["thread"] for r in control)


def test_the_example_in_the_docs_is_the_example_that_runs() -> None:
    root = Path(__file__).resolve().parents[2]
    example = (root / "examples" / "runtime_control.py").read_text(encoding="utf-8")
    docs = (root / "docs" / "control.md").read_text(encoding="utf-8")
    code = example.split('"""\n\n', 1)[1]
    assert f"```python\n{code}```" in docs
