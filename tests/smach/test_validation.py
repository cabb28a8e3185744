"""Whole-graph validation, reported all at once."""

from __future__ import annotations

import smach
from smach.testing import ScriptedState


def build_with_problems() -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["done", "never"])
    with sm:
        smach.StateMachine.add("A", ScriptedState(["go"]), transitions={"go": "B"})
        smach.StateMachine.add(
            "B", ScriptedState(["go", "stop"]), transitions={"go": "B", "stop": "done"}
        )
        smach.StateMachine.add("ORPHAN", ScriptedState(["go"]), transitions={"go": "done"})
        smach.StateMachine.add(
            "LOOP", ScriptedState(["again"], input_keys=["plan"]), transitions={"again": "LOOP"}
        )
    return sm


def test_validate_reports_every_graph_problem_with_its_path() -> None:
    report = smach.validate(build_with_problems())
    messages = {(i.path, i.message.split(" (")[0].split(":")[0]) for i in report.warnings}
    assert ("/ROOT/ORPHAN", "unreachable from initial state 'A'") in messages
    assert ("/ROOT/LOOP", "unreachable from initial state 'A'") in messages
    assert any(
        i.path == "/ROOT" and "'never' is never returned" in i.message for i in report.warnings
    )
    assert report.ok  # warnings only


def test_states_that_can_never_finish_are_warned_about() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add(
            "A", ScriptedState(["go", "end"]), transitions={"go": "SPIN", "end": "done"}
        )
        smach.StateMachine.add("SPIN", ScriptedState(["again"]), transitions={"again": "SPIN"})
    report = smach.validate(sm)
    assert [i.path for i in report.warnings if "no path" in i.message] == ["/ROOT/SPIN"]


def test_input_keys_nothing_provides_are_warned_and_provided_ones_are_not() -> None:
    sm = smach.StateMachine(outcomes=["done"], input_keys=["given"])
    sm.userdata.preset = 1
    with sm:
        smach.StateMachine.add(
            "WRITE",
            ScriptedState(["ok"], output_keys=["made"], writes={"made": 1}),
            transitions={"ok": "READ"},
        )
        smach.StateMachine.add(
            "READ",
            ScriptedState(["ok"], input_keys=["given", "preset", "made", "ghost", "local"]),
            transitions={"ok": "done"},
            remapping={"local": "elsewhere"},
        )
    report = smach.validate(sm)
    flagged = sorted(i.message.split("'")[1] for i in report.warnings if "input key" in i.message)
    assert flagged == ["ghost", "local"]
    assert any("remapped to 'elsewhere'" in i.message for i in report.warnings)


def test_nested_containers_are_validated_too() -> None:
    inner = smach.StateMachine(outcomes=["ok"])
    with inner:
        smach.StateMachine.add("X", ScriptedState(["ok"], input_keys=["missing"]))
    cc = smach.Concurrence(outcomes=["ok"], default_outcome="ok")
    with cc:
        smach.Concurrence.add("IN", inner)
        smach.Concurrence.add("Y", ScriptedState(["ok"], input_keys=["nope"]))
    report = smach.validate(cc)
    paths = sorted(i.path for i in report.warnings)
    assert paths == ["/ROOT/IN/X", "/ROOT/Y"]


def test_consistency_errors_appear_in_the_report_as_errors() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("A", ScriptedState(["go"]), transitions={"go": "NOWHERE"})
    report = smach.validate(sm)
    assert not report.ok
    assert report.errors[0].path == "/ROOT/A"
    assert "unknown target 'NOWHERE'" in report.errors[0].message
    assert str(report).startswith("error: /ROOT/A:")


def test_a_clean_machine_reports_no_problems() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", ScriptedState(["done"]))
    assert str(smach.validate(sm)) == "no problems found"
