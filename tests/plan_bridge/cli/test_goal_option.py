"""``--goal`` for PDDL problems: the goal given at run time replaces the problem's, as
ROSPlan's knowledge base fills ``(:goal (and))`` when a mission starts. Checked
against the domain and the problem (``--goal:1:COLUMN``), recorded in a run's
journal and taken from it by ``--resume``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from plan_bridge.cli import main
from smach.introspection.journal import read_journal

TOUR = Path(__file__).parent / "data" / "waypoint_tour"
DOMAIN = TOUR / "domain.pddl"
KB = TOUR / "problems" / "kb.pddl"  # (:goal (and)): filled at run time
OWN_GOAL = TOUR / "problems" / "tour.pddl"  # (:goal (and (visited wp2)))


def _lines(text: str, prefix: str) -> list[str]:
    return [line for line in text.splitlines() if line.startswith(prefix)]


def test_an_empty_goal_filled_with_goal_is_planned_run_and_checked(
    capsys: pytest.CaptureFixture[str],
) -> None:
    goal = "(visited wp2) (charging r1)"  # several formulas: their conjunction
    assert main(["plan", str(DOMAIN), str(KB), "--goal", goal, "--json"]) == 0
    captured = capsys.readouterr()
    plan = json.loads(captured.out)
    assert plan["status"] == "solved" and plan["goal"] == goal
    assert plan["plan"][-1] == "(plug-in r1)" and "(drive r1 wp1 wp2)" in plan["plan"]
    # The file's empty goal is gone: no warning about it, nothing replaced.
    assert _lines(captured.err, "warning:") == [] and _lines(captured.err, "note:") == []

    assert main(["run", str(DOMAIN), str(KB), "--goal", goal]) == 0
    err = capsys.readouterr().err
    assert f"plan-bridge run: waypoint_tour, problem kb.pddl, goal {goal} (" in err
    assert "summary: succeeded (goal reached)" in err and "[done] the goal already holds" not in err

    assert main(["check", str(DOMAIN), str(KB), "--goal", f"(and {goal})"]) == 0
    captured = capsys.readouterr()
    assert "kb.pddl: 2 actions, 5 objects, 2 goal atoms (given with --goal)" in captured.err
    assert "waypoint_tour: OK (1 problem(s) checked)" in captured.out


def test_without_goal_the_empty_goal_keeps_its_warning(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(DOMAIN), str(KB)]) == 0
    err = capsys.readouterr().err
    (warning,) = _lines(err, "warning:")
    assert "kb.pddl:8:3: the goal is empty" in warning
    assert "[done] the goal already holds" in err


def test_a_goal_of_the_file_replaced_is_said_in_a_note(capsys: pytest.CaptureFixture[str]) -> None:
    note = "note: --goal replaces the goal of tour.pddl: (:goal (and (visited wp2)))"
    for command in ("check", "plan", "run"):
        assert main([command, str(TOUR), "--problem", "tour", "--goal", "(visited wp3)"]) == 0
        captured = capsys.readouterr()
        assert _lines(captured.err, "note:") == [note], command
    assert main(["plan", str(TOUR), "--problem", "tour", "--goal", "(visited wp3)"]) == 0
    out = capsys.readouterr().out
    assert "1. (drive r1 dock wp3)" in out and "wp2" not in out  # the file's goal is not planned
    # --quiet: no note (nor anything else) on stderr.
    assert main(["run", str(TOUR), "--problem", "tour", "--goal", "(visited wp3)", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("goal", "expected"),
    [
        (
            "(visted wp2)",
            [
                "plan-bridge: error: --goal:1:2: undeclared predicate 'visted' in (:goal ...)",
                "    (visted wp2)",
                "     ^",
                "did you mean visited? declared: at, charging, linked, visited",
            ],
        ),
        (
            "(visited wp9)",
            [
                "plan-bridge: error: --goal:1:10: undeclared object or constant 'wp9' in (:goal ...)",
                "    (visited wp9)",
                "             ^",
                "did you mean wp3? declared: dock, r1, wp1, wp2, wp3",
            ],
        ),
        (
            "(visited wp1) (at wp1)",
            [
                "plan-bridge: error: --goal:1:15: at takes 2 argument(s), 1 given in (:goal ...)",
                "    (visited wp1) (at wp1)",
                "                  ^",
                f"declared as (at ?r - robot ?w - waypoint) at {DOMAIN}:7:17",
            ],
        ),
        (
            "(visited r1)",
            [
                "plan-bridge: error: --goal:1:10: r1 has type 'robot', but ?w of visited needs "
                "type 'waypoint' in (:goal ...)",
            ],
        ),
        (
            "(visited wp1",
            ["plan-bridge: error: --goal:1:1: unbalanced parentheses: a '(' is never closed"],
        ),
        (
            "visited wp1",
            ["plan-bridge: error: --goal:1:1: expected a goal formula (...), found 'visited'"],
        ),
        ("  ", ["plan-bridge: error: --goal: the goal is empty"]),
    ],
    ids=["predicate", "object", "arity", "type", "unbalanced", "bare-words", "empty"],
)
def test_a_bad_goal_is_bad_input_naming_what_and_what_is_allowed(
    goal: str, expected: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    errors = []
    for command in ("check", "plan", "run"):
        assert main([command, str(DOMAIN), str(KB), "--goal", goal]) == 2, command
        errors.append(capsys.readouterr().err)
    assert errors[0] == errors[1] == errors[2]  # the same verdict from every command
    assert errors[0].splitlines()[: len(expected)] == expected


def test_the_problems_other_findings_stay_at_their_lines(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # An error after a goal of several lines: the given goal is one line, yet the
    # error is at the same line and column with and without --goal.
    problem = tmp_path / "late_error.pddl"
    text = OWN_GOAL.read_text().replace("))))", ")))\n  (:metric minimize (mileage)))")
    problem.write_text(text)
    where = []
    for extra in ([], ["--goal", "(visited wp3)"]):
        assert main(["plan", str(DOMAIN), str(problem), *extra]) == 2
        (error,) = _lines(capsys.readouterr().err, "plan-bridge: error:")
        where.append(error)
    assert where[0] == where[1]
    assert f"{problem}:10:21: undeclared function 'mileage'" in where[0]


def test_a_problem_without_a_goal_section_gets_the_given_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    problem = tmp_path / "no_goal.pddl"
    problem.write_text(KB.read_text().replace("\n  (:goal (and)))", ")"))
    assert main(["plan", str(DOMAIN), str(problem)]) == 2
    assert "the problem has no (:goal ...) section" in capsys.readouterr().err
    assert main(["plan", str(DOMAIN), str(problem), "--goal", "(visited dock)"]) == 0
    assert "(drive r1 dock wp1)" in capsys.readouterr().out


def test_a_goal_may_name_the_domains_constants_and_any_formula(
    capsys: pytest.CaptureFixture[str],
) -> None:
    goal = "(and (visited dock) (not (charging r1)) (at r1 wp1))"
    assert main(["run", str(DOMAIN), str(KB), "--goal", goal, "--quiet", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["goal_reached"] and figures["executed"][-1] == "(drive r1 dock wp1)"


def test_a_goal_of_several_lines_with_comments(capsys: pytest.CaptureFixture[str]) -> None:
    goal = "(visited wp3) ; the far end\n(visited wp1)   ; on the way back\n"
    assert main(["plan", str(DOMAIN), str(KB), "--goal", goal, "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert plan["status"] == "solved" and plan["goal"] == "(visited wp3) (visited wp1)"
    assert {"wp1", "wp3"} <= {step.split()[-1].rstrip(")") for step in plan["plan"]}


def test_a_folder_with_goal_checks_the_problem_run_would_plan(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["check", str(TOUR), "--goal", "(visited wp1)"]) == 0
    captured = capsys.readouterr()
    assert "waypoint_tour: OK (1 problem(s) checked)" in captured.out
    assert "kb.pddl: 2 actions, 5 objects, 1 goal atoms (given with --goal)" in captured.err


def test_the_journal_keeps_the_goal_and_resume_takes_it_from_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "waypoint_tour"
    shutil.copytree(TOUR, folder)
    journal = tmp_path / "run.jsonl"
    goal = "(visited wp3) (visited wp1)"
    options = ["--problem", "tour", "--fail-rate", "0.3", "--seed", "4", "--quiet", "--json"]
    code = main(["run", str(folder), "--goal", goal, *options, "--journal", str(journal)])
    whole = json.loads(capsys.readouterr().out)
    assert code == 0 and whole["goal_reached"]
    header, _ = read_journal(journal)
    assert header["run"]["goal"] == goal and header["run"]["problem"].endswith("tour.pddl")

    # The run cut after its first checkpoint; the goal comes from the journal even if
    # the problem file's goal changed since.
    data = journal.read_bytes()
    first = data.index(b'{"kind": "checkpoint"')
    cut = data.index(b'{"kind": "checkpoint"', first + 1)
    killed = tmp_path / "killed.jsonl"
    killed.write_bytes(data[:cut])
    problem = folder / "problems" / "tour.pddl"
    problem.write_text(problem.read_text().replace("(visited wp2)", "(visited dock)"))
    assert main(["run", "--resume", str(killed), "--goal", goal]) == 2
    assert "the goal and events of the run come from the journal: give no --goal" in (
        capsys.readouterr().err
    )
    assert main(["run", "--resume", str(killed), "--json"]) == 0
    captured = capsys.readouterr()
    assert f"plan-bridge resuming: waypoint_tour, problem tour.pddl, goal {goal} (" in captured.err
    assert "note: --goal replaces the goal of tour.pddl: (:goal (and (visited dock)))" in (
        captured.err
    )
    resumed = json.loads(captured.out)
    assert resumed["goal_reached"]
    visits = {step.split()[-1].rstrip(")") for step in resumed["executed"]}
    assert {"wp1", "wp3"} <= visits


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_robot_node_started_with_ros_judges_the_given_goal(
    capsys: pytest.CaptureFixture[str],
) -> None:
    pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
    # The file's goal (visited wp2) is off the way to wp3: a robot node judging the
    # mission by it would report the goal not reached.
    args = ["--goal", "(visited wp3)", "--ros", "--quiet", "--json"]
    assert main(["run", str(DOMAIN), str(OWN_GOAL), *args]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["goal_reached"] and figures["executed"] == ["(drive r1 dock wp3)"]
