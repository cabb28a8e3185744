"""What `plan-bridge run` prints: one line per step, per plan and per recovery, then the
summary; `-v` adds the states each step enters. The default run shows a fault and
the recovery from it."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.cli import main

FETCH = Path(__file__).parents[3] / "domains" / "fetch_drink"


@pytest.mark.timeout(120)
def test_the_default_run_prints_steps_a_replan_with_its_reason_once_and_the_summary(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", str(FETCH)]) == 0
    lines = capsys.readouterr().err.splitlines()
    kinds = [line.split()[0] for line in lines]
    assert set(kinds) <= {"plan-bridge", "[plan]", "step", "[replan]", "summary:"}
    replans = [line for line in lines if line.startswith("[replan]")]
    assert len(replans) >= 1  # the default run shows what the project is for
    reason = replans[0].removeprefix("[replan] ")
    assert sum(reason in line for line in lines) == 1  # said once
    assert lines[-1].startswith("summary: succeeded (goal reached)")
    assert ", 0 faults injected" not in lines[-1]
    steps = [line for line in lines if line.startswith("  step ")]
    assert all(" -> " in line and line.endswith(" ms]") for line in steps)


@pytest.mark.timeout(120)
def test_verbose_output_adds_the_states_each_step_enters(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", str(FETCH), "-v"]) == 0
    lines = capsys.readouterr().err.splitlines()
    states = [line for line in lines if line.startswith("    /ROOT/PLAN/")]
    assert states and all("/SKILL/" in line for line in states)
