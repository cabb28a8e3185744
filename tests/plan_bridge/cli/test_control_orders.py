"""`plan-bridge control URL order | cancel | orders`: orders sent to a running mission
from a terminal (docs/orders.md, "Send orders while the mission runs")."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from controlled_mission import ControlledMission, control

from plan_bridge.cli import main
from plan_bridge.cli.control import ONE_GOAL, orders_table
from smach.introspection.journal import read_journal

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = pytest.mark.timeout(180)


class Mission(ControlledMission):
    """`plan-bridge run ROOMS --problem P --control --start-paused --json ...` in a
    subprocess. Started paused, so that a plan holds until `control resume`."""

    def __init__(self, problem: str, *extra: str) -> None:
        super().__init__(
            str(ROOMS), "--problem", problem, "--control", "--start-paused", "--json", *extra
        )


@pytest.fixture
def missions() -> Iterator[list[Mission]]:
    started: list[Mission] = []
    yield started
    for mission in started:
        mission.end()


def listing(capsys: pytest.CaptureFixture[str], url: str) -> dict[str, dict[str, Any]]:
    code, out, err = control(capsys, url, "orders", "--json")
    assert code == 0, err
    return {order["id"]: order for order in json.loads(out)}


def wait_orders(
    capsys: pytest.CaptureFixture[str],
    url: str,
    done: Callable[[dict[str, dict[str, Any]]], bool],
    what: str,
) -> dict[str, dict[str, Any]]:
    """Poll `control URL orders --json` until ``done(orders)`` (60 s at most)."""
    deadline = time.monotonic() + 60
    orders = listing(capsys, url)
    while not done(orders):
        if time.monotonic() > deadline:
            raise AssertionError(f"waited for {what}; the orders: {orders}")
        time.sleep(0.05)
        orders = listing(capsys, url)
    return orders


def status_of(orders: dict[str, dict[str, Any]], name: str) -> str:
    return str(orders.get(name, {}).get("status", ""))


# -- no run needed --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["order"], "order needs GOAL"),
        (["order", "  "], "order needs GOAL"),
        (["cancel"], "cancel needs the ID of an order"),
        (["cancel", "o1", "--priority", "2"], "--priority goes with order only, not cancel"),
        (["orders", "--id", "a", "--within", "5"], "--id and --within go with order only"),
        (["order", "(at", "r1", "office)"], "takes one argument; quote it, e.g. '(at r1 office)'"),
        (["order", "(at r1 office)", "--id", " "], "--id needs a name"),
    ],
)
def test_an_order_request_that_cannot_be_sent_exits_2_before_any_connection(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    code, out, err = control(capsys, "http://127.0.0.1:9/#token=abc", *args)
    assert code == 2 and out == ""
    assert message in err


def test_a_bad_priority_or_within_is_refused_by_the_argument_parser(
    capsys: pytest.CaptureFixture[str],
) -> None:
    for args in (["--priority", "high"], ["--within", "-3"], ["--within", "soon"]):
        with pytest.raises(SystemExit) as exited:
            main(["control", "http://127.0.0.1:9/#token=abc", "order", "(at r1 office)", *args])
        assert exited.value.code == 2
    assert "expected a positive number of seconds" in capsys.readouterr().err


def test_the_orders_table_has_status_robots_times_latency_and_reason() -> None:
    text = orders_table(
        [
            {"id": "cup", "status": "done", "robots": ["r1"], "arrived": 0.0, "ended": 4.0,
             "latency": 4.0},
            {"id": "late-one", "status": "done", "robots": ["r1", "r2"], "arrived": 1.0,
             "ended": 90.25, "latency": 89.25, "late": True},
            {"id": "bad", "status": "refused", "arrived": 4.0,
             "reason": "(at r9 office): unknown object 'r9'"},
            {"id": "o4", "status": "queued", "arrived": 5.5},
        ]
    )  # fmt: skip
    lines = text.splitlines()
    assert lines[0].split() == ["ID", "STATUS", "ROBOTS", "ARRIVED", "ENDED", "LATENCY", "REASON"]
    assert lines[1].split() == ["cup", "done", "r1", "0.0", "4.0", "4.0", "s"]
    assert lines[2].split() == ["late-one", "done", "r1,r2", "1.0", "90.2", "89.2", "s", "(late)"]
    assert lines[3].split()[:5] == ["bad", "refused", "-", "4.0", "-"]
    assert lines[3].endswith("(at r9 office): unknown object 'r9'")
    assert lines[4].split() == ["o4", "queued", "-", "5.5", "-", "-"]
    assert lines[5] == "4 orders: 2 done, 1 refused, 1 queued"
    assert orders_table([]) == "no orders yet"


# -- a running mission ------------------------------------------------------------------------


def test_orders_sent_from_the_command_line_are_planned_cancelled_listed_and_journaled(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    journal = tmp_path / "run.jsonl"
    mission = Mission("p02.pddl", "--orders-open", "--journal", str(journal))
    missions.append(mission)
    url = mission.url
    code, out, err = control(
        capsys, url, "order", "(at r2 office)", "--id", "r2-office", "--priority", "1",
        "--within", "60",
    )  # fmt: skip
    assert code == 0, err
    assert out.startswith("order r2-office: (at r2 office) (taken when the mission next looks")
    # Paused: the plan for it is made, and held before its first step.
    orders = wait_orders(
        capsys, url, lambda o: status_of(o, "r2-office") == "assigned", "r2-office assigned"
    )
    assert orders["r2-office"]["robots"] == ["r2"] and orders["r2-office"]["priority"] == 1
    assert orders["r2-office"]["deadline"] == orders["r2-office"]["arrived"] + 60
    code, out, err = control(capsys, url, "cancel", "r2-office", "no", "longer", "needed")
    assert code == 0, err
    assert out == "cancel: order r2-office cancelled: cancelled (cli): no longer needed\n"
    code, _, err = control(capsys, url, "cancel", "r2-office")
    assert code == 1
    assert "refused: order 'r2-office' is cancelled already" in err
    code, _, err = control(capsys, url, "cancel", "nope")
    assert (code, err.strip()) == (1, "plan-bridge: refused: no order 'nope'")
    assert control(capsys, url, "order", "(item-at cup office)", "--id", "cup")[0] == 0
    assert control(capsys, url, "order", "(at r9 office)", "--id", "bad")[0] == 0
    code, _, err = control(capsys, url, "order", "(at r1 hall)", "--id", "cup")
    assert code == 1 and "order id 'cup' is already used" in err
    assert control(capsys, url, "resume")[0] == 0
    orders = wait_orders(
        capsys,
        url,
        lambda o: status_of(o, "cup") == "done" and status_of(o, "bad") == "refused",
        "cup done and bad refused",
    )
    assert orders["cup"]["robots"] == ["r1"] and orders["cup"]["origin"] == "cli"
    assert "unknown object 'r9'" in orders["bad"]["reason"]
    code, out, _ = control(capsys, url, "orders")
    assert code == 0
    table = {line.split()[0]: line for line in out.splitlines()[1:-1]}
    assert table["cup"].split()[1:3] == ["done", "r1"] and table["cup"].rstrip().endswith(" s")
    assert "cancelled (cli): no longer needed" in table["r2-office"]
    assert "unknown object 'r9'" in table["bad"]
    assert out.splitlines()[-1] == "3 orders: 1 cancelled, 1 done, 1 refused"
    # Open for orders, the mission goes on until stopped.
    assert control(capsys, url, "preempt")[0] == 0
    mission.finish()
    counts = mission.figures()["orders"]
    assert (counts["done"], counts["refused"], counts["cancelled"]) == (1, 1, 1)
    _, records = read_journal(journal)
    changes = [(r["order"], r["status"]) for r in records if r.get("kind") == "order"]
    assert ("r2-office", "cancelled") in changes and ("cup", "done") in changes
    assert ("bad", "refused") in changes


def test_a_mission_of_one_goal_refuses_orders_saying_how_to_start_one(
    capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    mission = Mission("p01.pddl")
    missions.append(mission)
    for args in (["order", "(at robot1 office)"], ["cancel", "o1"], ["orders"]):
        code, out, err = control(capsys, mission.url, *args)
        assert (code, out) == (1, "")
        assert err.strip() == f"plan-bridge: refused: {ONE_GOAL}"
    assert control(capsys, mission.url, "preempt")[0] == 0
    mission.finish()


def test_a_mission_of_an_orders_file_takes_no_new_order_but_cancels_one_to_come(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    orders_file = tmp_path / "orders.yaml"
    orders_file.write_text(
        "orders:\n"
        "  - {id: now, at: 0, goal: (at r2 office)}\n"
        "  - {id: later, at: 500, goal: (at r1 office)}\n"
    )
    mission = Mission("p02.pddl", "--orders", str(orders_file))
    missions.append(mission)
    url = mission.url
    code, _, err = control(capsys, url, "order", "(item-at cup office)")
    assert code == 1 and "refused: the mission takes no more orders" in err
    assert "--orders-open" in err
    code, out, err = control(capsys, url, "cancel", "later", "--json")
    assert code == 0, err
    reply = json.loads(out)
    assert reply["data"]["status"] == "cancelled" and reply["data"]["id"] == "later"
    assert control(capsys, url, "resume")[0] == 0
    # Every order of the file accounted for: the mission ends by itself.
    assert mission.finish() in (0, 130)  # 130: the Ctrl-C reached it before its wait
    counts = mission.figures()["orders"]
    assert (counts["done"], counts["cancelled"], counts["orders"]) == (1, 1, 2)
