"""The viewer's control actions without a browser: ViewerControls.perform."""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

import pytest

import smach
from smach.control import ControlError, Controller
from smach.introspection.control_api import ViewerControls
from smach.testing import ScriptedState


@pytest.fixture
def controller() -> Iterator[Controller]:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "done"})
    with Controller(sm) as ctl:
        yield ctl


def last(ctl: Controller) -> tuple[str, str, str]:
    record = ctl.history[-1]
    return record.action, record.source, record.path


def test_each_core_action_reaches_the_controller_with_its_source(controller: Controller) -> None:
    controls = ViewerControls(controller)
    answer = controls.perform({"action": "pause", "source": "cli"})
    assert answer["ok"] is True and answer["status"]["state"] == "pausing"
    assert last(controller) == ("pause", "cli", "")
    controls.perform({"action": "resume"})
    assert last(controller)[:2] == ("resume", "viewer")
    controls.perform({"action": "step", "source": "somewhere else"}, source="ros")
    assert last(controller)[:2] == ("step", "ros")
    controls.perform({"action": "add_breakpoint", "pattern": "*/A"})
    controls.perform({"action": "toggle_breakpoint", "path": "/ROOT/B"})
    controls.perform({"action": "remove_breakpoint", "pattern": "*/A"})
    assert [r.action for r in controller.history][-3:] == [
        "add_breakpoint",
        "add_breakpoint",
        "remove_breakpoint",
    ]
    controls.perform({"action": "clear_breakpoints"})
    assert last(controller)[0] == "clear_breakpoints"
    controls.perform({"action": "preempt"})
    assert last(controller)[0] == "preempt"


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"action": "pause", "path": 3}, "'path' must be a string"),
        ({"action": "force_outcome"}, "force_outcome needs 'outcome'"),
        ({"action": "add_breakpoint"}, "add_breakpoint needs 'pattern'"),
        ({"action": "jump"}, "unknown control action 'jump'; actions: pause, resume"),
        ({"action": ["pause"]}, "unknown control action ['pause']"),
        ({"action": "remove_breakpoint", "pattern": "nope"}, "no breakpoint 'nope'"),
        ({"action": "force_outcome", "outcome": "ok"}, "no state is running"),
    ],
)
def test_a_request_that_cannot_be_done_is_a_value_error_with_its_reason(
    controller: Controller, body: Mapping[str, Any], message: str
) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        ViewerControls(controller).perform(body)


def test_extra_actions_get_the_body_and_answer_with_their_result(controller: Controller) -> None:
    seen: list[Mapping[str, Any]] = []

    def ping(body: Mapping[str, Any]) -> object:
        seen.append(body)
        return 42

    def refuse(body: Mapping[str, Any]) -> object:
        raise ValueError("not now")

    def crash(body: Mapping[str, Any]) -> object:
        raise ControlError("broken")

    controls = ViewerControls(
        controller, actions={"ping": ping, "refuse": refuse, "crash": crash, "quiet": seen.append}
    )
    assert controls.perform({"action": "ping", "n": 1}) == {"ok": True, "result": "42"}
    assert seen == [{"action": "ping", "n": 1, "source": "viewer"}]
    assert controls.perform({"action": "quiet"}) == {"ok": True, "result": None}
    with pytest.raises(ValueError, match=r"^not now$"):
        controls.perform({"action": "refuse"})
    with pytest.raises(ValueError, match=r"^crash failed: ControlError: broken$"):
        controls.perform({"action": "crash"})
    assert controls.status([])["actions"][-4:] == ["crash", "ping", "quiet", "refuse"]


def test_extra_actions_may_not_hide_the_core_ones(controller: Controller) -> None:
    with pytest.raises(ValueError, match=r"\['pause'\] would hide the built-in ones"):
        ViewerControls(controller, actions={"pause": print})
