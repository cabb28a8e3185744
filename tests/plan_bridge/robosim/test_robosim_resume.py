"""``plan-bridge run --resume`` of a pyrobosim mission: the journal's header keeps the
goal and the events file, the checkpoints the world (robot, objects, doors, battery,
clock, pending events, fault generators), so a killed run continues to the same end."""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import read_journal

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"
CLOSE = FETCH / "events" / "close_hallway.yaml"
#: What a resumed run must end with as the uninterrupted one did; and the simulated
#: time, to the millisecond (a checkpoint keeps the plan's timeline, so the resumed run
#: waits for each step's planned time as the killed one would have).
END = ("goal_reached", "executed", "faults_injected", "world_changes", "distance_m")


def _run_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    main(["run", *args, "--quiet", "--json"])
    data: dict[str, Any] = json.loads(capsys.readouterr().out)
    return data


@pytest.mark.timeout(300)
def test_a_robosim_mission_cut_at_random_points_and_resumed_ends_as_the_uninterrupted_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    whole = _run_json(
        capsys, str(FETCH), "--events", str(CLOSE), "--seed", "1", "--fail-rate", "0.3",
        "--journal", str(journal),
    )  # fmt: skip
    assert whole["goal_reached"] and whole["replans"] >= 1 and whole["faults_injected"] > 0
    data = journal.read_bytes()
    start, stop = data.index(b"\n") + 1, data.rfind(b'{"kind": "summary"')
    # Before the first checkpoint the events can only come from the journal's header.
    first_checkpoint = data.index(b'{"kind": "checkpoint"')
    rng = random.Random("robosim_fetch")
    cuts = [rng.randrange(start, first_checkpoint), *(rng.randrange(start, stop) for _ in range(2))]
    for n, cut in enumerate(cuts):
        killed = tmp_path / f"killed-{n}.jsonl"
        killed.write_bytes(data[:cut])  # a kill at that byte: torn last line included
        resumed = _run_json(capsys, "--resume", str(killed))
        ends = {k: (whole[k], resumed[k]) for k in END if whole[k] != resumed[k]}
        if abs(whole["sim_time_s"] - resumed["sim_time_s"]) > 0.0015:
            ends["sim_time_s"] = (whole["sim_time_s"], resumed["sim_time_s"])
        assert not ends, f"cut at byte {cut} of {len(data)}: {ends}"
        assert journal_problems(killed, every=5) == []


def test_the_journal_header_of_a_world_run_records_its_goal_name_goal_and_events(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    figures = _run_json(
        capsys, str(FETCH), "--problem", "open_fridge", "--events", str(CLOSE),
        "--fail-rate", "0", "--journal", str(journal),
    )  # fmt: skip
    assert figures["goal_reached"]
    header, _ = read_journal(journal)
    run = header["run"]
    assert run["problem"] == "open_fridge"
    assert run["goal"] == "(IsOpen fridge)"
    assert run["events"] == str(CLOSE)


def test_resume_refuses_a_goal_or_events_given_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    journal.write_text('{"kind": "header"}\n')
    assert main(["run", "--resume", str(journal), "--goal", "(IsOpen fridge)"]) == 2
    assert "give no --goal" in capsys.readouterr().err
    assert main(["run", "--resume", str(journal), "--events", str(CLOSE)]) == 2
    assert "give no --events" in capsys.readouterr().err
