"""What a run does not do: check a tree again, or build events nobody listens to."""

from __future__ import annotations

import logging

import pytest
from smach_helpers import Leaf

import smach
from smach.container import Container


def _nested(depth: int) -> list[smach.StateMachine]:
    """``depth`` machines, each holding the next; the leaf at the bottom. Outermost first."""
    inner: smach.State = Leaf(["done"])
    levels = []
    for _ in range(depth):
        sm = smach.StateMachine(["done"])
        with sm:
            smach.StateMachine.add("CHILD", inner, {"done": "done"})
        levels.append(sm)
        inner = sm
    return levels[::-1]


def _count_checks(monkeypatch: pytest.MonkeyPatch) -> dict[int, int]:
    checks: dict[int, int] = {}
    original = smach.StateMachine.consistency_problems

    def counting(self: smach.StateMachine) -> list[str]:
        checks[id(self)] = checks.get(id(self), 0) + 1
        return original(self)

    monkeypatch.setattr(smach.StateMachine, "consistency_problems", counting)
    return checks


def test_a_nested_tree_is_checked_once_and_again_only_where_it_changed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    levels = _nested(10)
    checks = _count_checks(monkeypatch)
    root = levels[0]
    for _ in range(3):
        assert root.execute() == "done"
    # Closed before the counting began: checked and compiled at close(), never per run.
    assert checks == {}
    bottom = levels[-1]
    with bottom:
        smach.StateMachine.add("EXTRA", Leaf(["done"]))
    assert root.execute() == "done"
    assert root.execute() == "done"
    # close() of the changed machine checked it once; the next run checked nothing.
    assert checks == {id(bottom): 1}


def test_a_machine_changed_after_close_is_checked_once_on_its_next_run_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    outer, inner = _nested(2)
    checks = _count_checks(monkeypatch)
    outer.userdata = smach.UserData()  # a change made without close()
    for _ in range(3):
        assert outer.execute() == "done"
    assert checks == {id(outer): 1}
    assert inner.execute() == "done"
    assert checks == {id(outer): 1}


def test_loggers_without_listeners_write_lines_and_build_no_event(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def no_event(*args: object, **kwargs: object) -> None:
        raise AssertionError("an event was built with nobody listening")

    for name in ("_emit_started", "_emit_entered", "_emit_exited", "report_transition"):
        monkeypatch.setattr(Container, name, no_event)
    monkeypatch.setattr(smach.StateMachine, "_emit_step", no_event)
    sm = smach.StateMachine(["done"])
    with sm:
        smach.StateMachine.add("A", Leaf(["next"]), {"next": "B"})
        smach.StateMachine.add("B", _nested(2)[0], {"done": "done"})
    it = smach.Iterator(
        outcomes=["done"],
        input_keys=[],
        output_keys=[],
        it=[1, 2],
        it_label="item",
        exhausted_outcome="done",
    )
    with it:
        smach.Iterator.set_contained_state("BODY", sm, loop_outcomes=["done"])
    lines: list[str] = []
    smach.set_loggers(lines.append, lines.append, lines.append, lines.append)
    try:
        assert it.execute() == "done"
    finally:
        smach.log.restore_default_loggers()
    assert "State machine transitioning 'A':'next'-->'B'" in lines
    assert sum(line.startswith("Iterating item") for line in lines) == 2


def test_a_python_logger_dropping_info_installed_as_loggers_gets_no_line_formatted(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def no_line(*args: object, **kwargs: object) -> None:
        raise AssertionError("a log line was formatted for a logger that drops INFO")

    for name in ("_log_started", "_log_transition", "_log_terminated"):
        monkeypatch.setattr(smach.StateMachine, name, no_line)
    logger = logging.getLogger("test_run_cost.robot")
    logger.setLevel(logging.WARNING)
    smach.set_loggers(logger.info, logger.warning, logger.debug, logger.error)
    try:
        assert not smach.log.info_enabled()
        assert _nested(3)[0].execute() == "done"
    finally:
        smach.log.restore_default_loggers()


def test_a_logger_whose_level_admits_info_or_cannot_tell_gets_the_lines() -> None:
    class RosLikeLogger:  # an rclpy logger answers get_effective_level() (INFO is 20)
        def __init__(self, level: int) -> None:
            self.level = level
            self.lines: list[str] = []

        def get_effective_level(self) -> int:
            return self.level

        def info(self, msg: str) -> None:
            self.lines.append(msg)

    quiet, chatty = RosLikeLogger(30), RosLikeLogger(20)
    plain: list[str] = []
    try:
        for info, expected in ((quiet.info, False), (chatty.info, True), (plain.append, True)):
            smach.set_loggers(info, plain.append, plain.append, plain.append)
            assert smach.log.info_enabled() is expected
        smach.set_loggers(chatty.info, plain.append, plain.append, plain.append)
        assert _nested(2)[0].execute() == "done"
    finally:
        smach.log.restore_default_loggers()
    assert sum(line.startswith("State machine starting") for line in chatty.lines) == 2


def test_the_starting_line_names_the_userdata_keys_of_each_run() -> None:
    sm = smach.StateMachine(["done"], input_keys=["a"])
    with sm:
        smach.StateMachine.add("ONLY", Leaf(["done"]), {"done": "done"})
    lines: list[str] = []
    smach.set_loggers(lines.append, lines.append, lines.append, lines.append)
    try:
        for keys in (["a"], ["a"], ["a", "b"], []):
            sm.userdata = smach.UserData({k: 1 for k in keys})
            assert sm.execute() == "done"
    finally:
        smach.log.restore_default_loggers()
    starts = [line for line in lines if line.startswith("State machine starting")]
    shown = [line.rsplit("\t", 1)[1] for line in starts]
    assert shown == ["['a']", "['a']", "['a', 'b']", "[]"]
