"""What `plan-bridge run` prints: one line per step, per plan and per recovery, then the
summary; `-v` adds the states each step enters. The default run shows a fault and
the recovery from it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from plan_bridge.cli import main

ROOT = Path(__file__).parents[3]
FETCH = ROOT / "domains" / "fetch_drink"


def readme_sample() -> list[str]:
    """The main job's output as README.md shows it (the block after `./dev run`)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"```\n(plan-bridge run: fetch_drink.*?)```", text, re.S)
    assert block is not None, "README.md has no sample of the main job's output"
    return block.group(1).splitlines()


def pattern(sample: str) -> str:
    """A sample line as a pattern: times may differ, `...` stands for anything."""
    out = []
    for part in re.split(r"(\.\.\.|\d+\.\d+ s|\[\d+ ms\])", sample):
        if part == "...":
            out.append(".*")
        elif re.fullmatch(r"\d+\.\d+ s", part):
            out.append(r"\d+\.\d+ s")
        elif re.fullmatch(r"\[\d+ ms\]", part):
            out.append(r"\[\d+ ms\]")
        else:
            out.append(re.escape(part))
    return "".join(out)


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


@pytest.mark.timeout(120)
def test_the_readme_shows_what_the_default_main_job_prints(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", str(FETCH)]) == 0
    lines = iter(capsys.readouterr().err.splitlines())
    for sample in readme_sample():
        if sample.strip() == "...":
            continue
        # Each sample line is printed, in this order (lines between them may be elided).
        assert any(re.fullmatch(pattern(sample), line) for line in lines), sample
