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
#: `./dev run`'s main job (the pyrobosim mission, a hallway closing), without the picture.
MAIN_JOB = [
    "run",
    "domains/robosim_fetch",
    "--events",
    "domains/robosim_fetch/events/close_hallway.yaml",
]


def readme_sample() -> list[str]:
    """The main job's output as README.md shows it (the block after `./dev run`)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"```\n(plan-bridge run: robosim_fetch.*?)```", text, re.S)
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
def test_a_run_with_a_fault_prints_steps_a_replan_with_its_reason_once_and_the_summary(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # Seed 2 injects a fault the plan must recover from (seed 0's plan, since the warm
    # planner chooses the route through the dining room, meets none that matters).
    assert main(["run", str(FETCH), "--seed", "2"]) == 0
    lines = capsys.readouterr().err.splitlines()
    kinds = [line.split()[0] for line in lines]
    summary = kinds.index("summary:")
    assert set(kinds[:summary]) <= {"plan-bridge", "[plan]", "step", "[replan]"}
    replans = [line for line in lines if line.startswith("[replan]")]
    assert len(replans) >= 1
    reason = replans[0].removeprefix("[replan] ")
    assert sum(reason in line for line in lines) == 1  # said once
    assert lines[summary] == "summary: succeeded (goal reached)"
    assert kinds[summary + 1 :] == ["actions:", "recovery:", "time:"]
    assert "; 0 faults injected" not in lines[summary + 1]
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
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")
    dev = (ROOT / "dev").read_text()
    assert " ".join(MAIN_JOB[1:]) in " ".join(dev.replace("\\\n", " ").split())
    monkeypatch.chdir(ROOT)
    picture = tmp_path / "run.svg"
    assert main([*MAIN_JOB, "--snapshot", str(picture)]) == 0
    lines = iter(capsys.readouterr().err.splitlines())
    for sample in readme_sample():
        if sample.strip() == "...":
            continue
        # Where ./dev run writes the picture, here tmp_path.
        expected = f"picture: {picture}" if sample.startswith("picture: ") else sample
        # Each sample line is printed, in this order (lines between them may be elided).
        assert any(re.fullmatch(pattern(expected), line) for line in lines), sample


def failed_steps_and_recover_lines(lines: list[str]) -> tuple[int, int]:
    """(failed steps beyond the first of each plan run, `[recover]` lines)."""
    beyond_first, failed = 0, 0
    for line in [*lines, "[end]"]:
        if line.startswith("  step "):
            failed += line.split(" -> ")[1].split()[0] in ("aborted", "invalid")
        elif line.startswith("[") and not line.startswith("[recover]"):
            beyond_first += max(0, failed - 1)
            failed = 0
    return beyond_first, sum(line.startswith("[recover] ") for line in lines)


@pytest.mark.timeout(120)
def test_a_temporal_run_prints_planned_times_in_planned_start_order(
    capsys: pytest.CaptureFixture[str],
) -> None:
    target = str(ROOT / "domains" / "timed_courier")
    assert main(["run", target, "--seed", "1", "--fail-rate", "0.3"]) == 0
    lines = capsys.readouterr().err.splitlines()
    plans = [line for line in lines if line.startswith("[plan] ")]
    assert plans and all(", makespan " in line for line in plans)
    run: list[tuple[int, float]] = []
    for line in [*lines, "[end]"]:
        step = re.fullmatch(
            r"  step (\d+): \(.*\) planned at (\d+\.\d\d) s for \d+\.\d\d s -> .*", line
        )
        if line.startswith("  step ") and " -> invalid [" in line:
            continue  # it did not start: no times
        if line.startswith("  step "):
            assert step is not None, line  # every step says when the plan starts it
            run.append((int(step.group(1)), float(step.group(2))))
        elif run:
            # One plan run: in step order, which is the planned start order.
            assert run == sorted(run) and [s for _, s in run] == sorted(s for _, s in run)
            run = []
    beyond_first, recovered = failed_steps_and_recover_lines(lines)
    assert recovered == beyond_first


@pytest.mark.timeout(120)
@pytest.mark.parametrize("seed", [2, 7])
def test_every_failed_step_of_a_concurrent_run_gets_its_own_recovery_line(
    seed: int, capsys: pytest.CaptureFixture[str]
) -> None:
    target = str(ROOT / "domains" / "two_robot_delivery")
    main(["run", target, "--concurrent", "--seed", str(seed), "--fail-rate", "0.5"])
    lines = capsys.readouterr().err.splitlines()
    beyond_first, recovered = failed_steps_and_recover_lines(lines)
    assert recovered == beyond_first
    assert all(" too: " in line for line in lines if line.startswith("[recover] "))
