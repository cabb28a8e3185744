"""A user's own container, written on the public extension API (docs/containers.md),
gets the run protocol and runtime control: pause, breakpoints and forced outcomes."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import pytest
from smach_helpers import Runner

import smach
from smach.container import construction_method
from smach.control import Controller
from smach.testing import BlockingState, EventRecorder, ScriptedState

pytestmark = pytest.mark.timeout(60)


class Fallback(smach.Container):
    """Try children in order until one returns ``success`` (the docs' example, typed)."""

    def __init__(self, success: str = "succeeded", failure: str = "failed") -> None:
        super().__init__([success, failure, "preempted"])
        self._success, self._failure = success, failure
        self._states: dict[str, smach.State] = {}
        self._remappings: dict[str, dict[str, str]] = {}
        self._child_uds: dict[str, smach.Remapper] = {}
        self._current: str | None = None

    @construction_method
    def add(
        self, label: str, state: smach.State, remapping: Mapping[str, str] | None = None
    ) -> smach.State:
        self.adopt_child(label, state)
        self._states[label] = state
        self._remappings[label] = dict(remapping or {})
        return state

    def get_children(self) -> dict[str, smach.State]:
        return self._states

    def get_initial_states(self) -> list[str]:
        return list(self._states)[:1]

    def get_active_states(self) -> list[str]:
        return [self._current] if self._current else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        return []

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: smach.UserData | None = None
    ) -> None:
        raise smach.InvalidStateError(f"{self.path}: a Fallback starts with its first child")

    def consistency_problems(self) -> list[str]:
        return [] if self._states else [f"{self.path}: no children"]

    def compile_children(self) -> None:
        self._child_uds = {
            label: self.child_remapper(label, state, self._remappings[label])
            for label, state in self._states.items()
        }

    def run_children(self) -> str | None:
        for label, state in self._states.items():
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            self._current = label
            try:
                result = self.step_child(label, state, self._child_uds[label])
            finally:
                self._current = None
            if result == self._success:
                return self._success
        return self._failure


def _mission(*children: tuple[str, smach.State]) -> tuple[smach.StateMachine, Fallback]:
    grasp = Fallback()
    for label, state in children:
        grasp.add(label, state)
    mission = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    mission.add("GRASP", grasp, transitions={"succeeded": "done"})
    return mission, grasp


def _try(outcome: str) -> ScriptedState:
    return ScriptedState([outcome], outcomes=["succeeded", "failed", "preempted"])


def test_a_pause_holds_the_next_child_of_a_users_container_until_resume() -> None:
    first = BlockingState(outcomes=("succeeded", "failed", "preempted"))
    second = _try("succeeded")
    mission, _ = _mission(("FROM_TOP", first), ("FROM_SIDE", second))
    ctl = Controller(mission)
    run = Runner(mission)
    assert first.started.wait(5)
    ctl.pause()
    first.release("failed")
    assert ctl.wait_for("paused", timeout=5)
    assert ctl.status().held == ("/ROOT/GRASP/FROM_SIDE",)
    assert second.call_count == 0
    ctl.resume()
    assert run.result() == "done"
    assert second.call_count == 1


def test_a_breakpoint_on_a_child_of_a_users_container_holds_it_before_it_starts() -> None:
    mission, _ = _mission(("FROM_TOP", _try("failed")), ("FROM_SIDE", _try("succeeded")))
    recorder = EventRecorder()
    mission.add_listener(recorder)
    ctl = Controller(mission)
    ctl.add_breakpoint("*/FROM_SIDE")
    run = Runner(mission)
    assert ctl.wait_for("at_breakpoint", timeout=5)
    assert ctl.status().breakpoint == "/ROOT/GRASP/FROM_SIDE"
    entered = [e.path for e in recorder.of_kind("state_entered")]
    assert entered == ["/ROOT/GRASP", "/ROOT/GRASP/FROM_TOP"]
    ctl.resume()
    assert run.result() == "done"


def test_force_outcome_of_a_running_child_of_a_users_container_replaces_its_outcome() -> None:
    first = BlockingState(outcomes=("succeeded", "failed", "preempted"))
    second = _try("failed")
    mission, _ = _mission(("FROM_TOP", first), ("FROM_SIDE", second))
    ctl = Controller(mission)
    run = Runner(mission)
    assert first.started.wait(5)
    ctl.force_outcome("succeeded")  # the active leaf: /ROOT/GRASP/FROM_TOP
    assert run.result() == "done"
    assert second.call_count == 0  # the forced success ended the fallback
    assert ctl.history[-1].action == "outcome_forced"
    assert ctl.history[-1].path == "/ROOT/GRASP/FROM_TOP"


def test_a_replaced_child_leaves_the_tree_and_its_replacement_reports_to_it() -> None:
    old, new = _try("succeeded"), _try("succeeded")
    mission, grasp = _mission(("ONLY", old))
    recorder = EventRecorder()
    mission.add_listener(recorder)
    grasp._states["ONLY"] = new
    grasp.replace_child("ONLY", new, old)
    assert (old.path, new.path) == ("", "/ROOT/GRASP/ONLY")
    assert mission.execute() == "done"
    assert (old.call_count, new.call_count) == (0, 1)
    assert "/ROOT/GRASP/ONLY" in [e.path for e in recorder.of_kind("state_exited")]


def test_a_container_adopted_after_it_was_compiled_reports_userdata_writes_at_its_new_path() -> (
    None
):
    writer = smach.CBState(lambda ud: setattr(ud, "x", 1) or "done", outcomes=["done"])
    writer.register_output_keys(["x"])
    inner = smach.StateMachine(outcomes=["done"])
    with inner:  # (closing compiles the views of its children)
        smach.StateMachine.add("WRITE", writer)
    outer = smach.StateMachine(outcomes=["done"])
    outer.add("INNER", inner)
    recorder = EventRecorder()
    outer.add_listener(recorder)
    assert outer.execute() == "done"
    assert [e.path for e in recorder.of_kind("userdata_written")] == ["/ROOT/INNER"]
