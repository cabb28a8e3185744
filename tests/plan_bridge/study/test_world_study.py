"""The study on a pyrobosim world: scripted vs planned with a hallway closing, and the
columns of a robot's world (distance driven, battery used) for every target."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from plan_bridge.study import RunSpec, read_results, run_study, write_report
from plan_bridge.study.runs import FIELDS

ROOT = Path(__file__).resolve().parents[3]
FETCH = str(ROOT / "domains" / "robosim_fetch")
ROOMS = str(Path(__file__).parents[1] / "data" / "rooms")


@pytest.mark.timeout(300)
def test_a_study_on_a_pyrobosim_world_reports_sim_time_distance_and_battery(
    tmp_path: Path,
) -> None:
    pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")
    specs = [
        RunSpec(FETCH, approach, 0.0, 0, variant="close_hallway_early")
        for approach in ("scripted", "planned")
    ]
    rows = {r["approach"]: r for r in run_study(specs, tmp_path, jobs=2)}
    for row in rows.values():
        assert row["goal_reached"] == "True", row["error"]
        # The world's own simulated time, metres and battery (charging counted back).
        assert 40 < float(row["sim_time_s"]) < 200
        assert float(row["distance_m"]) > 20 and float(row["battery_used"]) > 50
    assert rows["planned"]["replans"] == "1"  # the closed hallway, found on the way
    text = write_report(list(rows.values()), tmp_path, [], "plan-bridge study robosim_fetch")
    table = [
        line
        for line in text.read_text().splitlines()
        if line.startswith("| robosim_fetch (close_hallway_early) | scripted | 0 |")
    ]
    distance = f"{float(rows['scripted']['distance_m']):.1f}"
    battery = f"{float(rows['scripted']['battery_used']):.1f}"
    assert table and f"| {distance} | {battery} |" in table[0]


def test_an_older_results_file_gains_the_new_columns_and_other_worlds_leave_them_blank(
    tmp_path: Path,
) -> None:
    old = [f for f in FIELDS if f not in ("distance_m", "battery_used", "cpu_model")]
    row = dict.fromkeys(old, "") | {
        "target": "rooms", "approach": "planned", "fault_rate": "0", "seed": "0",
        "outcome": "succeeded", "goal_reached": "True", "wall_time_s": "0.5",
        "sim_time_s": "3", "host": "elsewhere",
    }  # fmt: skip
    with (tmp_path / "results.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=old)
        writer.writeheader()
        writer.writerow(row)
    rows = run_study([RunSpec(ROOMS, "planned", 0.0, 0)], tmp_path, jobs=1)
    with (tmp_path / "results.csv").open() as f:
        assert next(csv.reader(f)) == FIELDS
    assert len(read_results(tmp_path / "results.csv")) == 1  # the old row counts as done
    assert rows[0]["distance_m"] == rows[0]["battery_used"] == rows[0]["cpu_model"] == ""
    text = write_report(rows, tmp_path, [], "plan-bridge study rooms").read_text()
    line = next(x for x in text.splitlines() if x.startswith("| rooms | planned | 0 |"))
    assert "| 3.0 |  |  |" in line  # sim time, then no distance and no battery
    assert "`elsewhere` (CPU not recorded): 1" in text
