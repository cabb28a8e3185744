"""domains/robosim_hospital: three robots serve streams of orders on a hospital floor,
planned (the order mission of plan_bridge.orders) and scripted (a dispatcher, first come
first served, and a machine per order)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
import yaml

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main
from plan_bridge.missions.mission import ScriptedMission, load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.orders.order_executive import OrderExecutive
from plan_bridge.orders.order_file import load_orders
from plan_bridge.robosim.events import load_events
from plan_bridge.robosim.scripting import OrderLedger
from plan_bridge.robosim.target_files import read_goals
from plan_bridge.robosim.world import RobosimWorld

HOSPITAL = Path(__file__).resolve().parents[3] / "domains" / "robosim_hospital"
FINAL = {"done", "failed", "refused", "cancelled"}
FIGURES = {"orders", "done", "failed", "refused", "latency_p50_s", "latency_p95_s"}


def write_orders(tmp_path: Path, orders: list[dict[str, Any]], name: str = "orders") -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump({"orders": orders}), encoding="utf-8")
    return path


def steady_slice(tmp_path: Path, seed: int, minutes: float) -> Path:
    """The orders of steady.yaml (drawn with ``seed``) of its first ``minutes``, written out."""
    drawn = load_orders(HOSPITAL / "orders" / "steady.yaml").draw(seed)
    return write_orders(
        tmp_path,
        [
            {"id": o.id, "at": o.at, "goal": o.goal, "priority": o.priority}
            for o in drawn
            if o.at < 60 * minutes
        ],
        "steady_slice",
    )


def scripted(orders: Path | None, seed: int, **options: Any) -> ScriptedMission:
    target = load_target(HOSPITAL)
    assert target.module is not None
    mission: ScriptedMission = target.module.scripted(
        target.task, seed=seed, fail_rate=options.pop("fail_rate", 0.2), orders=orders, **options
    )
    return mission


def ledger_of(mission: ScriptedMission) -> OrderLedger:
    ledger = mission.extra["orders"]
    assert isinstance(ledger, OrderLedger)
    return ledger


def accounted(states: list[Any]) -> None:
    """Every order is final, and every one not done says why."""
    for state in states:
        assert state.status.value in FINAL, state.to_json()
        assert state.status.value == "done" or state.reason, state.to_json()


def test_every_goal_of_the_floor_and_of_its_order_streams_reads_in_the_world() -> None:
    target = load_target(HOSPITAL)
    for name in read_goals(HOSPITAL):
        assert target.read_order_goal(name)
    for file in ("steady", "rush", "demo"):
        schedule = load_orders(HOSPITAL / "orders" / f"{file}.yaml")
        goals = {goal for stream in schedule.streams for goal in stream.goals}
        goals |= {timed.order.goal for timed in schedule.written if "typo" not in timed.order.id}
        for goal in goals:
            assert target.read_order_goal(goal), goal


def test_the_rush_hour_brings_more_orders_in_its_quarter_hour_than_the_steady_hour() -> None:
    for seed in range(1, 6):
        counts = {
            name: sum(
                1
                for o in load_orders(HOSPITAL / "orders" / f"{name}.yaml").draw(seed)
                if 1200 <= o.at < 2100
            )
            for name in ("steady", "rush")
        }
        assert counts["rush"] > counts["steady"], (seed, counts)


def test_the_readme_demo_serves_every_order_and_refuses_the_typo_with_the_goals_there_are(
    capsys: pytest.CaptureFixture[str],
) -> None:
    demo = HOSPITAL / "orders" / "demo.yaml"
    assert main(["run", str(HOSPITAL), "--orders", str(demo), "--seed", "1", "--json"]) == 0
    out, err = capsys.readouterr()
    orders = json.loads(out)["orders"]
    assert (orders["orders"], orders["done"], orders["refused"], orders["failed"]) == (6, 5, 1, 0)
    assert "[order] typo refused" in err and "did you mean meds_to_a1?" in err


def test_planned_and_scripted_serve_the_same_orders_and_account_for_every_one(
    tmp_path: Path,
) -> None:
    orders = steady_slice(tmp_path, seed=3, minutes=9)
    mission = prepare_mission(
        load_target(HOSPITAL), MissionOptions(seed=3, fail_rate=0.2, orders=str(orders))
    )
    mission.run()
    planned = mission.executive
    assert isinstance(planned, OrderExecutive)
    baseline = scripted(orders, seed=3)
    assert baseline.machine.execute() == "succeeded"
    ledger = ledger_of(baseline)
    books = {"planned": planned.orders.states(), "scripted": ledger.orders.states()}
    # The same orders arrived at the same moments of the mission's clock.
    arrivals = {k: [(s.id, s.order.at) for s in v] for k, v in books.items()}
    assert arrivals["planned"] == arrivals["scripted"] and len(arrivals["planned"]) >= 4
    for states in books.values():
        accounted(states)
    figures = {"planned": planned.figures(), "scripted": ledger.figures()}
    for numbers in figures.values():
        assert set(numbers) >= FIGURES and set(numbers["busy_share"]) == {"nova", "orla", "pim"}
        assert numbers["done"] == numbers["orders"]
    assert baseline.world.figures()["distance_m"] > 0


def test_a_seeded_scripted_order_run_repeats_exactly(tmp_path: Path) -> None:
    orders = steady_slice(tmp_path, seed=4, minutes=5)
    ends = []
    for _ in range(2):
        mission = scripted(orders, seed=4)
        assert mission.machine.execute() == "succeeded"
        ledger = ledger_of(mission)
        ends.append(
            (
                ledger.figures(),
                mission.world.figures(),
                [s.to_json() for s in ledger.orders.states()],
            )
        )
    assert ends[0] == ends[1] and ends[0][1]["faults_injected"] > 0


def test_the_nearest_idle_robot_takes_an_order_and_a_second_order_for_its_kit_waits(
    tmp_path: Path,
) -> None:
    orders = write_orders(
        tmp_path,
        [
            {"id": "first", "at": 0, "goal": "(At meds_a bed_b2_top)"},
            {"id": "second", "at": 0, "goal": "(At meds_a bed_a1_top)"},
            {"id": "urgent", "at": 0, "goal": "(At sample_b lab_counter_top)", "priority": 1},
        ],
    )
    mission = scripted(orders, seed=0, fail_rate=0.0)
    assert mission.machine.execute() == "succeeded"
    book = ledger_of(mission).orders
    first, second, urgent = (book.get(name) for name in ("first", "second", "urgent"))
    # nova stands at the charger, next to the pharmacy: it takes the kit; the urgent
    # order went out first, to pim in ward B, next to the sample.
    assert (first.robots, urgent.robots) == (("nova",), ("pim",))
    assert [s.status.value for s in (first, second, urgent)] == ["done"] * 3
    assert second.started is not None and first.ended is not None
    assert second.started >= first.ended  # it waited for the kit
    assert mission.world.truth(("at", "meds_a", "bed_a1_top"))


def test_the_dispatcher_refuses_what_it_cannot_read_and_fails_an_order_behind_locked_doors(
    tmp_path: Path,
) -> None:
    orders = write_orders(
        tmp_path,
        [
            {"id": "typo", "at": 0, "goal": "meds_to_a7"},
            {"id": "door", "at": 0, "goal": "(IsOpen hall_corridor_icu)"},
            {"id": "icu", "at": 10, "goal": "(At meds_c bed_icu1_top)"},
            {"id": "ward", "at": 10, "goal": "(At meds_b bed_a2_top)"},
        ],
    )
    lock = tmp_path / "lock_icu.yaml"
    lock.write_text(
        "".join(
            f"- {{at: 1, {kind}: {hall}}}\n"
            for hall in ("hall_corridor_icu", "hall_icu_station")
            for kind in ("close", "lock")
        ),
        encoding="utf-8",
    )
    mission = scripted(orders, seed=0, fail_rate=0.0)
    world = mission.world
    assert isinstance(world, RobosimWorld)
    world.schedule(load_events(lock))
    assert mission.machine.execute() == "succeeded"
    book = ledger_of(mission).orders
    states = {s.id: s for s in book.states()}
    accounted(list(states.values()))
    assert states["typo"].status.value == "refused" and "did you mean" in states["typo"].reason
    assert states["door"].status.value == "refused" and "delivers objects" in states["door"].reason
    # A robot drove to the ICU, found both doors locked; no way is left to it.
    assert states["icu"].status.value == "failed" and "no way" in states["icu"].reason
    assert states["ward"].status.value == "done"


def _measure() -> ModuleType:
    spec = importlib.util.spec_from_file_location("hospital_measure", HOSPITAL / "measure.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up)
    spec.loader.exec_module(module)
    return module


def test_the_measure_script_tallies_what_became_of_every_order_and_the_bar(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    measure = _measure()
    args = ["--seeds", "1", "--orders", "demo", "--events", "doors", "--out", str(tmp_path)]
    assert measure.main(args) == 0
    out = capsys.readouterr().out
    # 6 orders: 5 done, the typo refused (it could not be done); none lost or done twice.
    assert "| doors | demo | 1 | 6 | 5 | 0 | 1 | 0 | 0 | 1 | 100.0% |" in out
    assert "typo: refused (could not be done)" in out
    assert (tmp_path / "doors-demo-1.out").is_file()  # kept: a second call reads it
    assert measure.main(args) == 0
    assert capsys.readouterr().out == out
