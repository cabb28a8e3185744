"""`plan-bridge import plansys2`: a PlanSys2 terminal commands file becomes a PDDL problem."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from plan_bridge.cli import main
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import get_planner

pytestmark = pytest.mark.timeout(120)

DOMAIN = """\
; A robot runs errands between rooms; its battery drains as it moves.
(define (domain errands)
  (:requirements :strips :typing :numeric-fluents)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?x - room) (connected ?a ?b - room)
               (battery_full ?r - robot) (battery_low ?r - robot))
  (:functions (battery ?r - robot))
  (:action move
    :parameters (?r - robot ?a ?b - room)
    :precondition (and (robot_at ?r ?a) (connected ?a ?b) (>= (battery ?r) 10))
    :effect (and (robot_at ?r ?b) (not (robot_at ?r ?a)) (decrease (battery ?r) 10))))
"""

COMMANDS = """\
# The house of my robot (written for this test).
set instance rover robot
set instance hall room
set instance study room
set instance attic room
set instance cellar room   # removed below, with what names it

set predicate (connected hall study)
set predicate (connected study hall)
set predicate (connected study attic)
set predicate (connected cellar hall)
set predicate (robot_at rover hall)
set predicate battery_full rover
set function (= (battery rover) 95.5)
set goal (and(robot_at rover cellar))

; PDDL comments too
get problem instances
remove instance cellar
remove predicate battery_full rover
set predicate (battery_low rover)
set goal (and (robot_at rover attic))
get plan
quit
set predicate (this line is never read)
"""


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path]:
    domain = tmp_path / "errands.pddl"
    domain.write_text(DOMAIN)
    commands = tmp_path / "house.commands"
    commands.write_text(COMMANDS)
    return domain, commands


def test_a_commands_file_becomes_a_problem_the_planner_solves(
    files: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, commands = files
    out = tmp_path / "house.pddl"
    assert main(["import", "plansys2", str(commands), "--domain", str(domain), "-o", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"{commands}:18: warning: 'get problem instances' skipped: the import builds the problem only",
        f"{commands}:23: warning: 'get plan' skipped: the import builds the problem only",
        f"plan-bridge import: wrote {out} (4 instances, 5 facts, 1 values, 1 goal atoms)",
    ]
    text = out.read_text()
    assert text.startswith(
        "; imported from house.commands by plan-bridge import plansys2\n"
        "(define (problem house)\n  (:domain errands)\n"
    )
    assert "cellar" not in text  # removed with its fact and goal atom, as PlanSys2 does
    assert "    (battery_low rover)\n" in text and "battery_full" not in text
    assert "    (= (battery rover) 95.5)\n" in text
    task = load_task(domain, out)
    assert task.goal_facts == (("robot_at", "rover", "attic"),)
    # A numeric problem: the planner `auto` chooses a numeric engine for it.
    result = get_planner("auto").solve(task, timeout=60)
    assert result.solved, result.explanation
    assert [str(step) for step in result.actions] == [
        "(move rover hall study)",
        "(move rover study attic)",
    ]


def test_without_output_the_problem_goes_to_stdout(
    files: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    domain, commands = files
    assert main(["import", "plansys2", str(commands), "--domain", str(domain), "--name", "p1"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("; imported from house.commands")
    assert "(define (problem p1)" in out and out.endswith(")\n")


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (
            "set predicate (robot_att rover hall)",
            "(robot_att rover hall): unknown predicate 'robot_att' (did you mean 'robot_at'?); "
            "predicates of domain errands: robot_at, connected, battery_full, battery_low",
        ),
        (
            "set predicate (robot_at rover kitchen)",
            "(robot_at rover kitchen): unknown object 'kitchen'; objects of type room: hall "
            "(add it first as an instance: kitchen - room)",
        ),
        (
            "set predicate (robot_at hall rover)",
            "(robot_at hall rover): 'hall' is a room, but ?r of robot_at takes a robot; "
            "objects of type robot: rover",
        ),
        ("set instance leia droid", "instance leia - droid: unknown type 'droid'"),
        ("set instance leia", "expected set instance NAME TYPE, e.g. set instance leia robot"),
        ("set function (= (battery rover) full)", "'full' is not a number"),
        ("set goal (or (robot_at rover hall))", "(or ...) is not supported"),
        ("set goal", "expected set goal (and (ATOM) ...)"),
        ("remove instance ghost", "no instance 'ghost'; instances: rover, hall"),
        ("remove instance hall rover", "expected remove instance NAME, e.g. remove instance leia"),
        ("remove predicate", "expected remove predicate (ATOM), e.g. (robot_at leia kitchen)"),
        ("set nothing at all", "unknown command 'set nothing at all'"),
        ("ros2 run plansys2_terminal plansys2_terminal", "unknown command 'ros2 run"),
        ("set predicate (robot_at rover hall", "unbalanced '('"),
    ],
)
def test_a_line_that_does_not_fit_is_reported_at_its_line_with_what_is_allowed(
    tmp_path: Path, line: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    domain = tmp_path / "errands.pddl"
    domain.write_text(DOMAIN)
    commands = tmp_path / "commands"
    commands.write_text(f"set instance rover robot\n\nset instance hall room\n{line}\nset goal\n")
    assert main(["import", "plansys2", str(commands), "--domain", str(domain)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"plan-bridge: error: {commands}:4: ")
    assert message in captured.err


def test_bad_files_are_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    domain = tmp_path / "errands.pddl"
    domain.write_text(DOMAIN)
    commands = tmp_path / "commands"
    commands.write_text("set instance rover robot\n")
    missing = tmp_path / "missing"
    assert main(["import", "plansys2", str(missing), "--domain", str(domain)]) == 2
    assert "cannot read the commands file" in capsys.readouterr().err
    broken = tmp_path / "broken.pddl"
    broken.write_text(DOMAIN.replace("(define (domain errands)", "(define (domain errands"))
    assert main(["import", "plansys2", str(commands), "--domain", str(broken)]) == 2
    assert f"plan-bridge: error: {broken}:" in capsys.readouterr().err
    nowhere = tmp_path / "no" / "such" / "dir" / "p.pddl"
    code = main(["import", "plansys2", str(commands), "--domain", str(domain), "-o", str(nowhere)])
    assert code == 2
    assert "cannot write the problem" in capsys.readouterr().err


def test_the_command_answers_without_loading_unified_planning(files: tuple[Path, Path]) -> None:
    domain, commands = files
    code = (
        "import sys\nfrom plan_bridge.cli import main\n"
        f"code = main(['import', 'plansys2', {str(commands)!r}, '--domain', {str(domain)!r}])\n"
        "assert 'unified_planning' not in sys.modules, 'unified-planning was imported'\n"
        "sys.exit(code)\n"
    )
    started = time.monotonic()
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert "(define (problem house)" in result.stdout
    assert time.monotonic() - started < 10
