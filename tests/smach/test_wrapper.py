"""Writing a new container type against the public Wrapper/Container interface."""

from __future__ import annotations

import itertools
import threading

import pytest

import smach
from smach.testing import BlockingState, EventRecorder, ScriptedState


class Fallback(smach.Wrapper):
    """A user container: run the child; if it fails, run it once more in 'safe mode'."""

    def run(self, child: smach.State, label: str) -> str:
        self._userdata["safe_mode"] = False
        outcome = self.run_child()
        if outcome == "aborted" and not self.preempt_requested():
            self._userdata["safe_mode"] = True
            outcome = self.run_child()
        return outcome


class Mode(smach.State):
    def __init__(self) -> None:
        super().__init__(outcomes=["succeeded", "aborted"], input_keys=["safe_mode"])
        self.modes: list[bool] = []

    def execute(self, ud: smach.UserData) -> str:
        self.modes.append(ud.safe_mode)
        return "succeeded" if ud.safe_mode else "aborted"


def test_custom_wrapper_runs_its_policy_through_run_child() -> None:
    mode = Mode()
    container = Fallback.wrap("DRIVE", mode)
    assert container.execute() == "succeeded"
    assert mode.modes == [False, True]


def test_custom_wrapper_gets_events_paths_and_callbacks_for_free() -> None:
    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add(
            "F",
            Fallback.wrap("DRIVE", Mode()),
            transitions={"succeeded": "done", "aborted": "failed", "preempted": "failed"},
        )
    recorder = EventRecorder()
    sm.add_listener(recorder)
    terminated: list[str | None] = []
    sm["F"].register_termination_cb(lambda ud, states, outcome: terminated.append(outcome))  # type: ignore[attr-defined]
    assert sm.execute() == "done"
    entered = [e.path for e in recorder.of_kind("state_entered")]
    assert entered == ["/ROOT/F", "/ROOT/F/DRIVE", "/ROOT/F/DRIVE"]
    assert terminated == ["succeeded"]
    assert smach.snapshot(sm).find("/ROOT/F/DRIVE") is not None


@pytest.mark.timeout(10)
def test_custom_wrapper_forwards_preempts_to_its_child() -> None:
    child = BlockingState(outcomes=["succeeded", "aborted", "preempted"])
    container = Fallback.wrap("X", child)
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(container.execute()))
    runner.start()
    assert child.started.wait(5)
    container.request_preempt()
    runner.join(5)
    assert result == ["preempted"]
    assert not container.preempt_requested()


def test_wrapper_run_returning_an_undeclared_outcome_is_an_error() -> None:
    class Broken(smach.Wrapper):
        def run(self, child: smach.State, label: str) -> str:
            self.run_child()
            return "nonsense"

    with pytest.raises(smach.InvalidTransitionError, match="nonsense"):
        Broken.wrap("X", ScriptedState(["done"])).execute()


def test_wrapper_without_child_reports_it() -> None:
    with pytest.raises(smach.InvalidTransitionError, match="has no child"):
        Fallback().execute()


class Alternate(smach.Container):
    """A multi-child container written from scratch: run children until one succeeds."""

    def __init__(self) -> None:
        super().__init__(outcomes=["succeeded", "aborted"])
        self._children: dict[str, smach.State] = {}
        self._active: str | None = None

    def add(self, label: str, state: smach.State) -> None:
        self._adopt_child(label, state)
        self._children[label] = state

    def execute(self, parent_ud: smach.UserData | None = None) -> str:
        self._begin(parent_ud)
        try:
            for label, child in self._children.items():
                self._active = label
                outcome = child.execute(self._remapper(label, child, None))
                if outcome == "succeeded":
                    return "succeeded"
            return "aborted"
        finally:
            self._active = None
            self._after_run()

    def get_children(self) -> dict[str, smach.State]:
        return self._children

    def get_initial_states(self) -> list[str]:
        return list(self._children)[:1]

    def get_active_states(self) -> list[str]:
        return [self._active] if self._active else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        labels = list(self._children)
        return [("aborted", a, b) for a, b in itertools.pairwise(labels)]

    def set_initial_state(
        self, initial_states: object, userdata: smach.UserData | None = None
    ) -> None:
        raise smach.InvalidStateError("Alternate always starts with its first child")

    def check_consistency(self) -> None:
        if not self._children:
            raise smach.InvalidStateError("Alternate needs children")


def test_container_written_from_scratch_nests_and_exports() -> None:
    alt = Alternate()
    alt.add("PLAN_A", ScriptedState(["aborted"], outcomes=["succeeded", "aborted"]))
    alt.add("PLAN_B", ScriptedState(["succeeded"], outcomes=["succeeded", "aborted"]))
    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add("TRY", alt, transitions={"succeeded": "done", "aborted": "failed"})
    assert sm.execute() == "done"
    node = smach.snapshot(sm)
    assert [c.label for c in node.find("/ROOT/TRY").children] == ["PLAN_A", "PLAN_B"]  # type: ignore[union-attr]
    assert '"/ROOT/TRY/PLAN_A" -> "/ROOT/TRY/PLAN_B"' in smach.to_dot(node)
