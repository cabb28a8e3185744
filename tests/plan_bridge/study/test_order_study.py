"""`plan-bridge study --orders`: planned and scripted serve the same order stream, and
the study compares them on orders done, latency, throughput and distance."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from plan_bridge.cli import main

ROOT = Path(__file__).resolve().parents[3]
HOSPITAL = ROOT / "domains" / "robosim_hospital"


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.timeout(600)
def test_a_study_of_an_order_stream_compares_planned_with_scripted_on_the_order_metrics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")
    out = tmp_path / "study"
    args = [
        "study",
        str(HOSPITAL),
        "--orders",
        "demo",
        "--seeds",
        "1,2",
        "--approaches",
        "scripted,planned",
    ]
    assert main([*args, "--fault-rates", "0.2", "--out", str(out), "--jobs", "2"]) == 0
    results = _rows(out / "results.csv")
    assert sorted((r["approach"], r["seed"]) for r in results) == [
        ("planned", "1"), ("planned", "2"), ("scripted", "1"), ("scripted", "2"),
    ]  # fmt: skip
    for row in results:
        assert row["orders"] == "demo" and row["error"] == "", row
        # demo.yaml: six orders, one of them names no goal of the world (refused).
        assert (row["orders_arrived"], row["orders_refused"]) == ("6", "1"), row
        assert int(row["orders_done"]) + int(row["orders_failed"]) == 5, row
        assert float(row["distance_m"]) > 0
    orders = _rows(out / "orders.csv")
    assert {r["approach"] for r in orders} == {"planned", "scripted"}
    metrics = {r["metric"] for r in _rows(out / "comparisons.csv") if r.get("orders") == "demo"}
    assert {"orders_done", "latency_p50", "latency_p95", "orders_per_hour"} <= metrics
    assert list(out.glob("orders_per_run*.png"))
    report = (out / "report.md").read_text()
    assert "orders done" in report and "demo" in report
