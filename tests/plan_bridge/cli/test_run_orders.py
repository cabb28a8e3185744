"""``plan-bridge run --orders``: a stream of orders from a file, every one accounted for."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from plan_bridge.cli import main

COURIERS = Path(__file__).parents[1] / "data" / "couriers"
ORDERS = COURIERS / "orders.yaml"

pytestmark = pytest.mark.timeout(240)


def test_a_run_of_orders_prints_each_change_and_the_orders_in_its_summary(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", str(COURIERS), "--orders", str(ORDERS), "--seed", "2", "--json"]) == 0
    captured = capsys.readouterr()
    figures = json.loads(captured.out)["orders"]
    assert figures["done"] + figures["refused"] == figures["orders"] > 10
    assert figures["refused"] == 2 and figures["not_arrived"] == 0
    err = captured.err
    assert "[order] p1-annex queued at 0.0 s: (lies p1 annex)" in err
    assert "[order] typo refused at " in err and "unknown object 'p7'" in err
    assert "[order] lost refused at " in err and "no robot can reach it" in err
    assert "summary: succeeded (no order failed)" in err
    assert f"  orders: {figures['orders']} arrived ({figures['done']} done, 2 refused)" in err


def test_a_bad_orders_file_stops_the_run_before_it_starts_naming_the_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "orders.yaml"
    bad.write_text("- at: 3\n  goal: (lies p1 west)\n- at: 5\n  gaol: (lies p2 west)\n")
    assert main(["run", str(COURIERS), "--orders", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:3: unknown key 'gaol' (did you mean goal?)" in err
    assert "Traceback" not in err


def test_the_journal_of_a_run_of_orders_holds_each_order_change(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from smach.introspection.journal import read_journal

    journal = tmp_path / "run.jsonl"
    assert (
        main(["run", str(COURIERS), "--orders", str(ORDERS), "--journal", str(journal), "--quiet"])
        == 0
    )
    capsys.readouterr()
    header, records = read_journal(journal)
    assert header["run"]["orders"] == str(ORDERS)
    changes = [r for r in records if r["kind"] == "order"]
    assert {r["status"] for r in changes} >= {"queued", "assigned", "active", "done", "refused"}
    done = [r for r in changes if r["status"] == "done"]
    assert all(r["latency"] is not None and r["arrived"] is not None for r in done)
    assert records[-1]["kind"] == "summary" and records[-1]["orders"]["refused"] == 2


def test_a_journal_keeps_a_long_goal_whole_for_a_resume(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from smach.introspection.journal import read_journal

    goal = " ".join(f"(lies p{n} {room})" for n in (1, 2, 3) for room in ("west",))
    goal = f"{goal} {' '.join('(in ann west)' for _ in range(12))}"
    assert len(goal) > 200  # (longer than an event's value is kept)
    journal = tmp_path / "run.jsonl"
    code = main(["run", str(COURIERS), "--goal", goal, "--journal", str(journal), "--quiet"])
    capsys.readouterr()
    assert code == 0
    header, _ = read_journal(journal)
    assert header["run"]["goal"] == goal
