"""Temporal missions in the study: the timed courier, its scripted baseline, ``auto``."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep
from plan_bridge.study.runs import APPROACHES, inapplicable

ROOT = Path(__file__).resolve().parents[3]
COURIER = ROOT / "domains" / "timed_courier"
FETCH_DRINK = ROOT / "domains" / "fetch_drink"


def courier_module() -> object:
    sys.path.insert(0, str(ROOT / "domains"))
    try:
        import timed_courier
    finally:
        sys.path.remove(str(ROOT / "domains"))
    return timed_courier


@pytest.mark.timeout(300)
def test_the_timed_courier_joins_the_study_with_its_script_and_kairos(tmp_path: Path) -> None:
    out = tmp_path / "study"
    done = subprocess.run(
        [
            *(str(Path(sys.executable).with_name("plan-bridge")), "study", str(COURIER)),
            *("--problem", "p01", "--runs", "2", "--fault-rates", "0"),
            *("--approaches", "scripted,planned,pyperplan", "--jobs", "2", "--out", str(out)),
        ],
        capture_output=True,
        text=True,
        timeout=280,
        env={
            **os.environ,
            "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
            "ROS_DOMAIN_ID": os.environ.get("ROS_DOMAIN_ID", "117"),
        },
    )
    assert done.returncode == 0, done.stderr[-2000:]
    # pyperplan plans classical problems only: left out, and the study says why.
    assert "approach 'pyperplan': pyperplan does not plan temporal" in done.stderr
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["approach"], r["seed"]) for r in rows) == [
        ("planned", "0"),
        ("planned", "1"),
        ("scripted", "0"),
        ("scripted", "1"),
    ]
    assert all(r["goal_reached"] == "True" and r["error"] == "" for r in rows)
    # auto chose Kairos for the temporal problem; the script has no planner.
    assert {r["approach"]: r["planner"] for r in rows} == {"planned": "kairos", "scripted": ""}
    # The makespan of a temporal run, in plan seconds: at least the plan's 24 s of
    # the courier's own actions (recharge 2, drives 6 + 6, doors 3 + 3, grab, hand-over).
    assert all(float(r["sim_time_s"]) >= 24 for r in rows)
    report = (out / "report.md").read_text()
    assert "`planned` (full, auto: kairos)" in report
    assert "Planners: kairos (up-kairos " in report
    assert "| timed_courier | drift | 1 |" in report
    # Wall times of a temporal mission include playing its timeline: the report says so.
    assert "a temporal mission: both include playing the timeline" in report


def test_an_approach_whose_engine_cannot_plan_the_problem_kind_is_inapplicable() -> None:
    courier = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    classical = load_task(FETCH_DRINK / "domain.pddl", FETCH_DRINK / "problems" / "p01.pddl")
    assert "temporal" in inapplicable("pyperplan", courier)
    assert {a for a in APPROACHES if not inapplicable(a, courier)} == set(APPROACHES) - {
        "pyperplan"
    }
    assert not any(inapplicable(a, classical) for a in APPROACHES)


def test_the_courier_world_draws_the_same_faults_whichever_robot_starts_first() -> None:
    world_class = courier_module().skills.CourierWorld  # type: ignore[attr-defined]
    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    hold = PlanStep("hold-door", ("helper", "hall", "lab"))
    drive = PlanStep("drive", ("courier", "depot", "hall"))
    for seed in range(12):
        first, second = (world_class(task, seed=seed, fail_rate=0.6) for _ in range(2))
        a = {str(s): first.begin(s) for s in (hold, drive)}
        b = {str(s): second.begin(s) for s in (drive, hold)}
        assert a == b
        assert all(started for started, _ in a.values())
    # ... and the faults do differ between seeds (the draws are not all alike).
    drawn = {
        frozenset(world_class(task, seed=seed, fail_rate=0.6).begin(drive)[1]) for seed in range(12)
    }
    assert len(drawn) > 1


@pytest.mark.timeout(120)
def test_the_scripted_courier_holds_the_fire_door_while_it_passes() -> None:
    courier = courier_module()
    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p02.pddl")
    mission = courier.scripted(task, seed=0, fail_rate=0.0)  # type: ignore[attr-defined]
    mission.world.time_scale = 0.002
    assert mission.machine.execute() == "succeeded"
    assert mission.world.goal_reached()
    # Both parcels delivered, box1 through the fire door (hold-door with pass-door).
    assert mission.world.values["(delivered)"] == 2
    assert {f.kind for f in mission.world.faults} == set()


def test_a_source_is_dirty_only_for_edits_of_code_not_of_reports(tmp_path: Path) -> None:
    from plan_bridge.study.environment import source_revision

    def git(*args: str) -> None:
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True)

    (tmp_path / "src").mkdir()
    (tmp_path / "docs").mkdir()
    (tmp_path / "src" / "code.py").write_text("x = 1\n")
    (tmp_path / "docs" / "report.md").write_text("old\n")
    git("init", "-q")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one")
    clean = source_revision(tmp_path / "src")
    assert len(clean) == 40 and "+" not in clean
    (tmp_path / "docs" / "report.md").write_text("a study rewrote its report\n")
    assert source_revision(tmp_path / "src") == clean
    (tmp_path / "src" / "code.py").write_text("x = 2\n")
    assert source_revision(tmp_path / "src") == clean + "+dirty"


def test_the_scripted_courier_refuses_a_door_no_helper_can_hold(tmp_path: Path) -> None:
    problem = (COURIER / "problems" / "p01.pddl").read_text()
    moved = problem.replace("(at helper hall)", "(at helper depot)")
    assert moved != problem
    (tmp_path / "p.pddl").write_text(moved)
    task = load_task(COURIER / "domain.pddl", tmp_path / "p.pddl")
    with pytest.raises(
        ValueError, match=r"helper \(depot\) stands at neither side of the fire door hall-lab"
    ):
        courier_module().scripted(task, seed=0, fail_rate=0.0)  # type: ignore[attr-defined]
