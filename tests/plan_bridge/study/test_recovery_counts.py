"""The study records, per mission, the planner calls, replans and repairs (issue 19)."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.study import RunSpec, read_results, run_study
from plan_bridge.study.runs import FIELDS

ROOMS = str(Path(__file__).parents[1] / "data" / "rooms")
COUNTS = ("planner_calls", "replans", "repairs", "retries", "continues")


@pytest.mark.timeout(300)
def test_every_run_of_a_study_records_its_planner_calls_replans_and_repairs(
    tmp_path: Path,
) -> None:
    assert set(COUNTS) <= set(FIELDS)
    runs = [
        RunSpec(ROOMS, approach, 0.5, seed)
        for approach in ("planned", "replan-only")
        for seed in (0, 1)
    ]
    run_study(runs, tmp_path / "study", jobs=1)
    rows = read_results(tmp_path / "study" / "results.csv")
    assert len(rows) == 4
    for row in rows:
        counts = {k: int(row[k]) for k in COUNTS}  # integers in every row
        assert counts["planner_calls"] >= 1, row  # the first plan at least
        if int(row["actions_failed"]):
            # Each failure was handled by one of the recovery layers and counted.
            assert sum(counts[k] for k in COUNTS[1:]) >= 1, row
    failed = [r for r in rows if r["approach"] == "replan-only" and int(r["actions_failed"])]
    assert failed, "a fault rate of 0.5 made some action fail"
    # replan-only sends every failure to the planner: no retry, no repair; every
    # planner call after the first plan is a replan (a replan may also reuse a plan).
    for row in failed:
        assert int(row["retries"]) == 0 and int(row["repairs"]) == 0, row
        assert 0 <= int(row["planner_calls"]) - 1 <= int(row["replans"]) and int(row["replans"]), (
            row
        )


def test_the_study_summary_shows_planner_calls_replans_and_repairs_per_run(
    tmp_path: Path,
) -> None:
    from plan_bridge.study.report import summarise_results, write_report

    base = {name: "0" for name in FIELDS}
    base.update(target="rooms", variant="", orders="", approach="planned", fault_rate="0.2")
    base.update(outcome="succeeded", goal_reached="True", wall_time_s="1.0")
    rows = [
        {**base, "seed": "0", "planner_calls": "3", "replans": "2", "repairs": "1"},
        {**base, "seed": "1", "planner_calls": "1", "replans": "0", "repairs": "4"},
    ]
    (summary,) = summarise_results(rows)
    assert (summary["mean_planner_calls"], summary["mean_replans"], summary["mean_repairs"]) == (
        2.0,
        1.0,
        2.5,
    )
    report = write_report(rows, tmp_path, [], "plan-bridge study rooms").read_text()
    header = next(line for line in report.splitlines() if "planner calls/run" in line)
    row = next(line for line in report.splitlines() if line.startswith("| rooms | planned |"))
    columns = [c.strip() for c in header.split("|")]
    cells = [c.strip() for c in row.split("|")]
    assert [
        cells[columns.index(c)] for c in ("planner calls/run", "replans/run", "repairs/run")
    ] == [
        "2.00",
        "1.00",
        "2.50",
    ]
