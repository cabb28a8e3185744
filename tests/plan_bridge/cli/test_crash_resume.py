"""Crash and resume: SIGKILL a journaled run at many points, resume it, lose nothing."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.cli import main
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import read_journal, read_states

ROOMS = Path(__file__).parents[1] / "data" / "rooms"


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "plan_bridge", *args]


def _kill_after_lines(journal: Path, lines: int, seed: int) -> bool:
    """Start a journaled run and SIGKILL it once the journal has ``lines`` lines.

    Returns False if the run finished before that.
    """
    process = subprocess.Popen(
        _cli(
            "run",
            str(ROOMS),
            "--fail-rate",
            "0.3",
            "--seed",
            str(seed),
            "--journal",
            str(journal),
            "--quiet",
        ),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    if _journal_shows(process, journal, lambda data: data.count(b"\n") >= lines):
        os.kill(process.pid, signal.SIGKILL)
    process.wait(30)
    # A kill that lands after the summary was written (the process was shutting down)
    # did not cut the run: it finished before the kill point.
    finished = b'{"kind": "summary"' in journal.read_bytes() if journal.exists() else False
    return process.returncode == -signal.SIGKILL and not finished


def _journal_shows(
    process: subprocess.Popen[Any], journal: Path, seen: Callable[[bytes], bool]
) -> bool:
    """Wait until ``seen(journal bytes)`` while ``process`` runs (60 s at most);
    False if the process ended first."""
    deadline = time.monotonic() + 60
    while process.poll() is None and time.monotonic() < deadline:
        if journal.exists() and seen(journal.read_bytes()):
            return True
        time.sleep(0.002)
    return False


def _resume_to_the_end(journal: Path) -> None:
    """``plan-bridge run --resume JOURNAL`` in a process of its own; it must succeed."""
    result = subprocess.run(
        _cli("run", "--resume", str(journal), "--quiet"),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr


@pytest.mark.timeout(600)
@pytest.mark.parametrize("lines", [2, 6, 12, 20, 30, 45, 60])
def test_a_run_killed_at_any_point_resumes_to_the_goal_without_redoing_finished_steps(
    tmp_path: Path, lines: int
) -> None:
    journal = tmp_path / "run.jsonl"
    if not _kill_after_lines(journal, lines, seed=4):
        pytest.skip("the run finished before the kill point")
    header, before = read_journal(journal)
    checkpoints = read_states(before, "checkpoint")
    done_before = len(checkpoints[-1]["state"]["report"]["executed"]) if checkpoints else 0
    first_after = checkpoints[-1]["state"]["first_index"] if checkpoints else 1

    _resume_to_the_end(journal)

    header_after, records = read_journal(journal)
    assert header_after == header  # one journal, appended to
    resumed_at = max(i for i, r in enumerate(records) if r["kind"] == "resumed")
    after = records[resumed_at:]
    finished_after = [
        r for r in after if r["kind"] == "step_finished" and r["outcome"] == "succeeded"
    ]
    # Steps that were done (checkpointed) are never run again: numbering continues.
    assert all(r["index"] >= first_after for r in finished_after)
    summary = records[-1]
    assert summary["kind"] == "summary" and summary["goal_reached"] is True
    assert len(summary["executed"]) == done_before + len(finished_after)
    # The journal of a resumed run keeps the rules (structures, replay) as a whole.
    assert journal_problems(journal, every=7) == []


DOMAINS = Path(__file__).parents[3] / "domains"
MISSIONS = [
    ("fetch_drink", 1, False),
    ("table_clearing", 1, False),
    ("recharge", 1, False),
    ("door_opening", 1, False),
    ("two_robot_delivery", 0, True),
    ("timed_courier", 3, True),  # temporal and numeric: overlapping steps, planned times
]
END = ("goal_reached", "executed", "faults_injected", "sim_time_s")


def _run_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    main(["run", *args, "--quiet", "--json"])
    data: dict[str, Any] = json.loads(capsys.readouterr().out)
    return data


@pytest.mark.timeout(600)
@pytest.mark.parametrize(("domain", "seed", "concurrent"), MISSIONS)
def test_a_mission_cut_at_random_points_and_resumed_ends_as_the_uninterrupted_run(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    domain: str,
    seed: int,
    concurrent: bool,
) -> None:
    journal = tmp_path / "run.jsonl"
    whole = _run_json(
        capsys, str(DOMAINS / domain), "--seed", str(seed), "--fail-rate", "0.3",
        "--journal", str(journal),
    )  # fmt: skip
    data = journal.read_bytes()
    rng = random.Random(f"{domain}{seed}")
    start, stop = data.index(b"\n") + 1, data.rfind(b'{"kind": "summary"')
    for n in range(3):
        cut = rng.randrange(start, stop)  # a kill at that byte: torn last line included
        killed = tmp_path / f"killed-{n}.jsonl"
        killed.write_bytes(data[:cut])
        resumed = _run_json(capsys, "--resume", str(killed))
        assert resumed["goal_reached"], f"cut at byte {cut}"
        if not concurrent:
            # Concurrent steps still running at the kill run again from where they
            # were (docs/reliability.md): only sequential missions end identically.
            ends = {k: (whole[k], resumed[k]) for k in END if whole[k] != resumed[k]}
            assert not ends, f"cut at byte {cut} of {len(data)}: {ends}"
        assert journal_problems(killed, every=5) == []


def test_resume_refuses_a_finished_run_and_a_foreign_file(tmp_path: Path) -> None:
    journal = tmp_path / "done.jsonl"
    done = subprocess.run(
        _cli("run", str(ROOMS), "--journal", str(journal), "--quiet"),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    again = subprocess.run(
        _cli("run", "--resume", str(journal)), capture_output=True, text=True, timeout=60
    )
    assert again.returncode == 2 and "already finished" in again.stderr
    foreign = tmp_path / "foreign.jsonl"
    foreign.write_text('{"kind": "header"}\n')
    refused = subprocess.run(
        _cli("run", "--resume", str(foreign)), capture_output=True, text=True, timeout=60
    )
    assert refused.returncode == 2 and "not a journal of 'plan-bridge run" in refused.stderr
    both = subprocess.run(
        _cli("run", str(ROOMS), "--resume", str(journal)),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert both.returncode == 2 and "give no TARGET" in both.stderr


@pytest.mark.timeout(300)
def test_a_resumed_run_keeps_its_time_scale_unless_given_another(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    _run_json(
        capsys, str(DOMAINS / "timed_courier"), "--seed", "3", "--time-scale", "0.002",
        "--journal", str(journal),
    )  # fmt: skip
    data = journal.read_bytes()
    # Cut before the second step started: the rest runs in the resumed process.
    second = data.index(b'"kind": "action_started"', data.index(b'"kind": "action_started"') + 1)
    cut = data.rfind(b"\n", 0, second) + 1

    def resumed_scales(*extra: str) -> set[float]:
        killed = tmp_path / f"killed{len(extra)}.jsonl"
        killed.write_bytes(data[:cut])
        assert _run_json(capsys, "--resume", str(killed), *extra)["goal_reached"]
        _, records = read_journal(killed)
        after = records[[r["kind"] for r in records].index("resumed") :]
        return {r["time_scale"] for r in after if r["kind"] == "action_started"}

    assert resumed_scales() == {0.002}  # from the journal's header
    assert resumed_scales("--time-scale", "0") == {0.0}  # given again: that one


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("sig", "code", "message"), [
    (signal.SIGTERM, 143, "plan-bridge: terminated"),
    (signal.SIGINT, 130, "plan-bridge: interrupted"),
])  # fmt: skip
def test_a_terminated_or_interrupted_run_closes_its_journal_and_resumes_to_the_goal(
    tmp_path: Path, sig: signal.Signals, code: int, message: str
) -> None:
    journal = tmp_path / "run.jsonl"
    process = subprocess.Popen(
        _cli(
            "run",
            str(DOMAINS / "fetch_drink"),
            "--time-scale",
            "0.05",
            "--journal",
            str(journal),
            "--quiet",
        ),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert _journal_shows(process, journal, lambda data: b'"kind": "checkpoint"' in data), (
        "the run ended before its first checkpoint"
    )
    process.send_signal(sig)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == code, stderr
    assert stderr.strip().splitlines()[-1] == message  # no traceback
    _, records = read_journal(journal)
    # Every line whole, no summary (the run did not end), and a record of why it stopped.
    assert records[-1] == {"kind": "interrupted", "signal": sig.name}
    assert all(r["kind"] != "summary" for r in records)

    _resume_to_the_end(journal)
    _, records = read_journal(journal)
    assert records[-1]["kind"] == "summary" and records[-1]["goal_reached"] is True
    assert journal_problems(journal, every=5) == []
