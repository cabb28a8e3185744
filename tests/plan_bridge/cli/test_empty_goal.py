"""An empty goal, ``(:goal (and))`` (ROSPlan-style problems fill it at run time), is
valid PDDL that plans nothing: `check`, `plan` and `run` warn about it at its line."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from plan_bridge.cli import main

ROOT = Path(__file__).parents[3]


def empty_goal_folder(tmp_path: Path) -> tuple[Path, int]:
    """The recharge mission with its first problem's goal emptied; (folder, goal line)."""
    folder = tmp_path / "recharge"
    shutil.copytree(ROOT / "domains" / "recharge", folder)
    problems = sorted((folder / "problems").glob("*.pddl"))
    for extra in problems[1:]:
        extra.unlink()
    text = problems[0].read_text()
    start = text.index("(:goal")
    end = text.rindex(")")  # the problem's own closing parenthesis
    problems[0].write_text(text[:start] + "(:goal (and))" + text[end:])
    return folder, text[:start].count("\n") + 1


@pytest.mark.timeout(120)
def test_check_plan_and_run_warn_about_an_empty_goal_at_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder, line = empty_goal_folder(tmp_path)
    warnings = []
    for command in ("check", "plan", "run"):
        assert main([command, str(folder)]) == 0
        err = capsys.readouterr().err
        warnings.append([row for row in err.splitlines() if row.startswith("warning: ")])
    assert warnings[0] == warnings[1] == warnings[2]
    (warning,) = warnings[0]
    assert f"p01.pddl:{line}:" in warning
    assert "the goal is empty" in warning
    assert "`run` ends at once (the goal already holds)" in warning


@pytest.mark.timeout(120)
def test_a_run_with_an_empty_goal_ends_at_once_as_the_warning_says(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder, _ = empty_goal_folder(tmp_path)
    assert main(["run", str(folder)]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert "[done] the goal already holds" in lines
    assert "  actions: 0 run, 0 failed" in "\n".join(lines)
    assert not any(line.startswith("[plan]") for line in lines)
