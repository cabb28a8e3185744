"""The study harness: runs, resumability, summaries, plots and report."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from plan_bridge.study import (
    RunSpec,
    authoring_cost,
    read_results,
    run_study,
    summarise_results,
    wilson,
    write_report,
)

ROOMS = str(Path(__file__).parents[1] / "data" / "rooms")


def specs(seeds: range) -> list[RunSpec]:
    return [
        RunSpec(ROOMS, a, r, s) for a in ("planned", "no-replan") for r in (0.0, 0.5) for s in seeds
    ]


@pytest.mark.timeout(300)
def test_study_runs_every_configuration_and_resumes_without_duplicates(tmp_path: Path) -> None:
    out = tmp_path / "study"
    rows = run_study(specs(range(2)), out, jobs=2)
    assert len(rows) == 8
    assert {r["outcome"] for r in rows} <= {"succeeded", "aborted"}
    assert all(r["goal_reached"] == "True" for r in rows if r["approach"] == "planned")
    # A second study with one more seed only runs the new seed.
    calls: list[RunSpec] = []
    rows = run_study(
        specs(range(3)), out, jobs=1, progress=lambda d, t, spec, row, e: calls.append(spec)
    )
    assert len(rows) == 12
    assert {c.seed for c in calls} == {2} and len(calls) == 4
    assert len(read_results(out / "results.csv")) == 12


@pytest.mark.timeout(300)
def test_a_killed_study_keeps_finished_rows_and_a_torn_row_is_rerun(tmp_path: Path) -> None:
    out = tmp_path / "study"
    run_study(specs(range(1)), out, jobs=1)
    results = out / "results.csv"
    lines = results.read_text().splitlines()
    # Simulate a crash mid-write: the last row is cut in the middle.
    results.write_text("\n".join(lines[:-1]) + "\n" + lines[-1][:10])
    rows = run_study(specs(range(1)), out, jobs=1)
    assert len(rows) == 4
    with results.open() as f:
        complete = [r for r in csv.DictReader(f) if r.get("outcome")]
    assert len(complete) == 4


def test_wilson_interval_brackets_the_proportion() -> None:
    low, high = wilson(18, 20)
    assert 0.68 < low < 0.9 < high < 0.98
    assert wilson(0, 0) == (0.0, 0.0)


@pytest.mark.timeout(300)
def test_report_has_summary_plots_and_findings(tmp_path: Path) -> None:
    rows = run_study(specs(range(2)), tmp_path, jobs=2)
    summary = summarise_results(rows)
    planned = [s for s in summary if s["approach"] == "planned" and s["fault_rate"] == 0.5]
    assert planned[0]["runs"] == 2
    report = write_report(rows, tmp_path, authoring_cost(ROOMS), "plan-bridge study rooms")
    text = report.read_text()
    assert "## Findings" in text and "fault rate 0.5" in text
    for name in (
        "summary.csv",
        "authoring.csv",
        "success_vs_fault_rate.png",
        "time_and_actions.png",
    ):
        assert (tmp_path / name).stat().st_size > 0
