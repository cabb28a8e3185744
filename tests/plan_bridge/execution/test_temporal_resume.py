"""Checkpoints of a temporal, numeric mission keep the planned times and the numbers, so
a resumed run dispatches the rest of the plan on its timeline with the belief's values
(killed runs resumed at random points: tests/plan_bridge/cli/test_crash_resume.py)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.cli import main
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import read_journal, read_states

DOMAINS = Path(__file__).parents[3] / "domains"

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def journal(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("resume") / "run.jsonl"
    main(
        [
            "run",
            str(DOMAINS / "timed_courier"),
            "--seed",
            "3",
            "--fail-rate",
            "0.3",
            "--journal",
            str(path),
            "--quiet",
        ]
    )
    return path


def _values(state: dict[str, Any]) -> dict[str, float]:
    return {fact: value for fact, value in state["values"]}


def test_every_checkpoint_of_a_temporal_plan_has_the_steps_left_times_and_the_numbers(
    journal: Path,
) -> None:
    _, records = read_journal(journal)
    checkpoints = [c["state"] for c in read_states(records, "checkpoint")]
    assert len(checkpoints) >= 2
    for state in checkpoints:
        assert len(state["timing"]) == len(state["plan"])
        assert all(start >= 0 and duration >= 0 for start, duration in state["timing"])
        assert "(charge-level courier)" in _values(state)


def test_every_checkpoint_has_each_robot_somewhere_even_while_it_drives(journal: Path) -> None:
    # A drive removes (at robot from) at its start and adds (at robot to) at its end; a
    # checkpoint written by another step meanwhile keeps the robot where it began (a
    # belief with the robot at no place is a state no planner can start from).
    _, records = read_journal(journal)
    for n, checkpoint in enumerate(read_states(records, "checkpoint")):
        places = [
            fact.split()[1] for fact in checkpoint["state"]["belief"] if fact.startswith("(at ")
        ]
        assert sorted(places) == ["courier", "helper"], (n, places)


def test_a_run_resumed_after_a_checkpoint_keeps_the_timeline_and_the_numeric_belief(
    journal: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = journal.read_bytes().splitlines(keepends=True)
    header, records = read_journal(journal)
    assert header["run"]["target"].endswith("timed_courier")
    # Cut after the second checkpoint (the courier has driven: its charge went down).
    positions = [i for i, r in enumerate(records) if r["kind"] == "checkpoint"]
    checkpoints = read_states(records, "checkpoint")
    first_charge = _values(checkpoints[0]["state"])["(charge-level courier)"]
    kept = checkpoints[1]["state"]
    assert kept["plan"]
    cut_at = positions[1] + 2  # the header's line, then the records up to that one
    killed = tmp_path / "killed.jsonl"
    killed.write_bytes(b"".join(lines[:cut_at]))
    main(["run", "--resume", str(killed), "--quiet", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert report["goal_reached"] is True
    assert report["makespan_planned"] is not None  # still a temporal run

    _, after = read_journal(killed)
    resumed_at = max(i for i, r in enumerate(after) if r["kind"] == "resumed")
    starts = [r for r in after[resumed_at:] if r["kind"] == "action_started"]
    assert starts, "the rest of the plan ran on the temporal dispatcher"
    timing = dict(zip(kept["plan"], map(tuple, kept["timing"]), strict=True))
    first = starts[0]
    assert (first["planned_start"], first["planned_duration"]) == timing[first["action"]]
    assert first["index"] >= kept["first_index"]
    # The numbers carried over: the courier's charge never goes back up to where it began.
    later = read_states(after[resumed_at:], "checkpoint")
    charge = _values(kept)["(charge-level courier)"]
    assert charge <= first_charge
    assert all(_values(c["state"])["(charge-level courier)"] <= charge for c in later)


def _kill_after_starts(journal: Path, starts: int) -> bool:
    """Run timed_courier journaled (at a watchable pace) and SIGKILL it once ``starts``
    actions started; False if it finished before."""
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    process = subprocess.Popen(
        [sys.executable, "-m", "plan_bridge", "run", str(DOMAINS / "timed_courier"),
         "--seed", "3", "--fail-rate", "0.3", "--time-scale", "0.02",
         "--journal", str(journal), "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while process.poll() is None and time.monotonic() < deadline:
        if journal.exists() and journal.read_bytes().count(b'"action_started"') >= starts:
            os.kill(process.pid, signal.SIGKILL)
            break
        time.sleep(0.005)
    process.wait(30)
    return process.returncode == -signal.SIGKILL


@pytest.mark.parametrize("starts", [3, 9])
def test_a_killed_temporal_mission_resumes_to_the_goal_without_redoing_finished_steps(
    tmp_path: Path, starts: int
) -> None:
    journal = tmp_path / "run.jsonl"
    if not _kill_after_starts(journal, starts):
        pytest.skip("the run finished before the kill point")
    _, before = read_journal(journal)
    checkpoints = read_states(before, "checkpoint")
    done_before = len(checkpoints[-1]["state"]["report"]["executed"]) if checkpoints else 0
    first_after = checkpoints[-1]["state"]["first_index"] if checkpoints else 1
    resumed = subprocess.run(
        [sys.executable, "-m", "plan_bridge", "run", "--resume", str(journal), "--quiet"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stderr
    _, records = read_journal(journal)
    resumed_at = max(i for i, r in enumerate(records) if r["kind"] == "resumed")
    after = records[resumed_at:]
    finished = [r for r in after if r["kind"] == "step_finished" and r["outcome"] == "succeeded"]
    assert all(r["index"] >= first_after for r in finished)  # numbering goes on, no redo
    assert any(r["kind"] == "action_started" for r in after)  # dispatched as a temporal plan
    summary = records[-1]
    assert summary["kind"] == "summary" and summary["goal_reached"] is True
    assert len(summary["executed"]) == done_before + len(finished)
    assert journal_problems(journal, every=7) == []
