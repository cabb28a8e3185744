"""Every command takes FOLDER [--problem P] and DOMAIN PROBLEM, with one verdict."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from plan_bridge.cli import main

DATA = Path(__file__).parents[1] / "data" / "rooms"
DOMAIN = DATA / "domain.pddl"
PROBLEM = DATA / "problems" / "p01.pddl"


FORMS = [[str(DATA)], [str(DATA), "--problem", "p01"], [str(DOMAIN), str(PROBLEM)]]
FORM_IDS = ["folder", "folder-problem-name", "domain-problem"]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("target", FORMS, ids=FORM_IDS)
def test_plan_takes_a_folder_or_a_domain_and_a_problem(
    target: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", *target, "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["status"] == "solved"
    assert Path(payload["problem"]).name == "p01.pddl"


@pytest.mark.timeout(120)
@pytest.mark.parametrize("target", FORMS, ids=FORM_IDS)
def test_check_and_run_take_a_folder_or_a_domain_and_a_problem(
    target: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["check", *target]) == 0
    checked = capsys.readouterr().out
    assert "p01.pddl: " in checked  # a folder without --problem: all its problems
    assert f"OK ({1 + (target == [str(DATA)])} problem(s) checked)" in checked
    assert main(["run", *target, "--quiet", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["goal_reached"] is True and Path(report["problem"]).name == "p01.pddl"


def test_two_different_problems_are_a_bad_input_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    other = DATA / "problems" / "p02.pddl"
    for command in ("check", "plan", "run"):
        assert main([command, str(DOMAIN), str(PROBLEM), "--problem", str(other)]) == 2
        assert "two problems given" in capsys.readouterr().err


def test_a_domain_file_without_a_problem_is_the_same_error_for_every_command(
    capsys: pytest.CaptureFixture[str],
) -> None:
    messages = []
    for command in ("check", "plan", "run"):
        assert main([command, str(DOMAIN)]) == 2
        messages.append(capsys.readouterr().err)
    assert messages[0] == messages[1] == messages[2]
    assert "a domain file needs a problem file" in messages[0]


def test_a_problem_naming_another_domain_is_planned_with_a_warning_by_every_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # ROSPlan's knowledge base writes problems with a placeholder domain name.
    problem = tmp_path / "p.pddl"
    text = PROBLEM.read_text()
    name = text.split("(:domain", 1)[1].split(")", 1)[0].strip()
    problem.write_text(text.replace(f"(:domain {name})", "(:domain elsewhere)"))
    for command in ("check", "plan", "run"):
        assert main([command, str(DOMAIN), str(problem)]) == 0
        err = capsys.readouterr().err
        assert f"{problem}:" in err and "this problem is for domain 'elsewhere'" in err
        assert f"planning it with {name!r}" in err


def test_findings_print_a_warning_line_then_a_note_line_on_stderr(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from plan_bridge.cli.base import Findings

    Findings(["the goal is empty"], notes=["the goal replaces (at a)"]).show()
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == "warning: the goal is empty\nnote: the goal replaces (at a)\n"
