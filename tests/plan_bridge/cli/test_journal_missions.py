"""The journal rules hold for every shipped mission, across replans, retries and
concurrent layers (resumes: test_crash_resume.py checks the same rules)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from plan_bridge.cli import main
from plan_bridge.skills.ros.entries import runs_on_ros
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import read_journal

DOMAINS = Path(__file__).parents[3] / "domains"

# Every mission folder in domains/ (a new one is checked without editing this file),
# each with seeds whose run at fail rate 0.2 has at least one fault and a recovery.
SEEDS = {"two_robot_delivery": (0, 1)}  # seed 0: the two robots' layers run concurrently
# (Not the folders whose skills.toml binds actions to ROS 2: they need a robot running.)
MISSIONS = sorted(
    d.name for d in DOMAINS.iterdir() if (d / "domain.pddl").is_file() and not runs_on_ros(d)
)
RUNS = [(domain, seed) for domain in MISSIONS for seed in SEEDS.get(domain, (1,))]


def test_the_journal_rules_are_checked_for_every_mission_in_domains() -> None:
    assert {"fetch_drink", "timed_courier", "two_robot_delivery"} <= set(MISSIONS)
    assert set(SEEDS) <= set(MISSIONS)


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("domain", "seed"), RUNS)
def test_every_event_of_a_mission_journal_refers_to_the_structure_in_force_and_replays_exactly(
    tmp_path: Path, domain: str, seed: int, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    main(
        [
            "run",
            str(DOMAINS / domain),
            "--seed",
            str(seed),
            "--fail-rate",
            "0.2",
            "--journal",
            str(journal),
            "--quiet",
            "--json",
        ]
    )
    report = json.loads(capsys.readouterr().out)
    assert report["replans"] + report["retries"] + report["repairs"] >= 1  # it recovered
    assert journal_problems(journal) == []
    _, records = read_journal(journal)
    structures = [r for r in records if r["kind"] == "structure"]
    # One structure per plan machine, written when it starts, and nothing else.
    plan_starts = [
        r for r in records if r["kind"] == "container_started" and r["path"] == "/ROOT/PLAN"
    ]
    assert [r["path"] for r in structures] == ["/ROOT/PLAN"] * len(plan_starts)
    assert [r["time"] for r in structures] == [r["time"] for r in plan_starts]
    # Bytes per action stay small: 4-14 KB measured (docs/performance.md); a structure
    # copy per new path or whole checkpoints made it 24 KB and growing with the plan.
    assert journal.stat().st_size / max(1, report["actions_executed"]) < 20_000


@pytest.mark.timeout(120)
def test_view_check_accepts_a_faithful_journal_and_names_what_is_wrong_in_another(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal = tmp_path / "run.jsonl"
    main(["run", str(DOMAINS / "fetch_drink"), "--seed", "1", "--journal", str(journal),
          "--quiet"])  # fmt: skip
    capsys.readouterr()
    assert main(["view", str(journal), "--check"]) == 0
    assert "OK" in capsys.readouterr().out
    # Without the structure of the second plan, its events refer to states not drawn.
    lines = journal.read_text().splitlines(keepends=True)
    second = [i for i, line in enumerate(lines) if '"kind": "structure"' in line][1]
    broken = tmp_path / "broken.jsonl"
    broken.write_text("".join(lines[:second] + lines[second + 1 :]))
    assert main(["view", str(broken), "--check"]) == 1
    out = capsys.readouterr().out
    assert "which the structure in force does not have" in out
