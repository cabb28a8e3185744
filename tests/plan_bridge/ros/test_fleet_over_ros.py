"""A fleet over ROS 2: the world in one process, each robot in its own; a robot's process
killed, its orders go to the others, and an order sent over ROS 2 meanwhile is planned
for (``plan-bridge run --ros`` on robosim_hospital)."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from waiting import wait_until

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from order_operator import Operator

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[3]
HOSPITAL = ROOT / "domains" / "robosim_hospital"
ORDERS = """\
orders:
  - {id: meds-a1, at: 0, goal: meds_to_a1}
  - {id: sample-b, at: 0, goal: sample_b_to_lab}
  - {id: linen-a2, at: 1, goal: linen_to_a2}
  - {id: meds-b2, at: 2, goal: meds_to_b2}
"""


def records(journal: Path, kind: str) -> list[dict[str, Any]]:
    """The journal's records of ``kind`` so far."""
    if not journal.exists():
        return []
    found = []
    for line in journal.read_text().splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue  # the line being written
        if record.get("kind") == kind:
            found.append(record)
    return found


def order_events(journal: Path) -> list[dict[str, Any]]:
    return records(journal, "order")


@pytest.mark.timeout(300)
def test_killing_a_robots_node_moves_its_orders_to_the_other_robots(tmp_path: Path) -> None:
    orders, journal = tmp_path / "orders.yaml", tmp_path / "run.jsonl"
    orders.write_text(ORDERS)
    command = [
        sys.executable, "-m", "plan_bridge", "run", str(HOSPITAL), "--ros", "-v",
        "--orders", str(orders), "--seed", "2", "--fail-rate", "0", "--time-scale", "0.05",
        "--journal", str(journal), "--orders-open",
    ]  # fmt: skip
    process = subprocess.Popen(
        command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    lines: list[str] = []
    reader = threading.Thread(
        target=lambda: lines.extend(line.rstrip("\n") for line in process.stderr or ()),
        daemon=True,
    )
    reader.start()
    try:
        # Each robot's node is a process of its own, beside the world's.
        pids: dict[str, int] = {}

        def started() -> bool:
            for line in list(lines):
                found = re.match(r"ros: robot node of (\w+) .*\(started here, pid (\d+)\)", line)
                if found:
                    pids[found[1]] = int(found[2])
            return len(pids) == 3

        assert wait_until(started, 120), "\n".join(lines)
        assert sorted(pids) == ["nova", "orla", "pim"] and len(set(pids.values())) == 3

        # The first robot that drives for an order is killed mid-drive (SIGKILL).
        def driving() -> str | None:
            for line in list(lines):
                found = re.match(r"  \[(\w+)\]   state /navigate/DRIVE", line)
                if found:
                    return found[1]
            return None

        assert wait_until(lambda: driving() is not None, 120), "\n".join(lines)
        victim = driving()
        assert victim is not None
        os.kill(pids[victim], signal.SIGKILL)
        killed_at = time.monotonic()
        theirs = {str(e["order"]) for e in order_events(journal) if victim in (e["robots"] or [])}
        # An order sent over ROS 2 while the mission runs, a robot short.
        operator = Operator("/orders")
        try:
            assert operator.call("submit", "meds_to_icu1") == (True, "o1")
            assert wait_until(lambda: "done" in operator.statuses("o1"), 200), operator.status
        finally:
            operator.close()

        def settled() -> bool:
            final = [e for e in order_events(journal) if e["status"] in ("done", "failed")]
            return len({e["order"] for e in final}) == 5

        assert wait_until(settled, 200), order_events(journal)
        settled_at = time.monotonic()
        process.send_signal(signal.SIGINT)  # open for orders: it runs until stopped
        process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    reader.join(5)
    text = "\n".join(lines)
    assert "Traceback" not in text
    # Every order is accounted for: done, or failed with its reason (none lost).
    final = {e["order"]: e for e in order_events(journal) if e["status"] in ("done", "failed")}
    assert sorted(final) == ["linen-a2", "meds-a1", "meds-b2", "o1", "sample-b"]
    gone = [d for d in records(journal, "executive_decision") if d["decision"] == "gone"]
    assert gone and victim in gone[0]["reason"], gone
    # The order sent over ROS 2 was planned for, without the victim.
    assert final["o1"]["status"] == "done" and victim not in final["o1"]["robots"]
    # The victim's orders were taken over: done by the others, none by the victim.
    assert theirs, "the killed robot had no order"
    moved = [o for o in theirs if final[o]["status"] == "done"]
    assert moved, {o: final[o] for o in theirs}
    for order in moved:
        assert victim not in (final[order]["robots"] or []), final[order]
    for order in theirs - set(moved):
        assert final[order]["reason"], final[order]
    taken = [e for e in order_events(journal) if e["order"] in moved and e["status"] == "assigned"]
    took = taken[-1]
    print(
        f"\n{victim} killed; its orders {sorted(theirs)} went to {took['robots']}; "
        f"every order final {settled_at - killed_at:.1f} s after the kill: "
        f"{sorted((o, e['status'], e['robots']) for o, e in final.items())}"
    )


def skill_server(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "plan_bridge.ros.skill_server", *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


@pytest.mark.timeout(240)
def test_world_and_robot_nodes_started_by_hand_run_a_mission_with_no_robot() -> None:
    """As on two machines: the world node and each robot's node started by hand (their
    own seed and fault rate count), the executive connects with --no-robot."""
    two = str(ROOT / "domains" / "robosim_two_robots")
    nodes = [
        skill_server(two, "--prefix", "fleet", "--seed", "3"),
        *(skill_server(two, "--prefix", "fleet", "--robot", name) for name in ("ada", "bob")),
    ]
    try:
        for node in nodes:
            assert node.stdout is not None and node.stdout.readline().strip() == "ready"
        run = subprocess.run(
            [sys.executable, "-m", "plan_bridge", "run", two, "--ros", "--no-robot",
             "--ros-prefix", "fleet", "--json"],
            cwd=ROOT, capture_output=True, text=True, timeout=150,
        )  # fmt: skip
    finally:
        for node in nodes:
            node.send_signal(signal.SIGTERM)
        outputs = [node.communicate(timeout=30)[0] for node in nodes]
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["goal_reached"] and report["seed"] == 3
    assert "ros: robot node of ada /robot_ada (already running)" in run.stderr
    assert "the world on /fleet" in run.stderr
    # Each robot ran its own steps in its own process; the world counted the faults.
    for name, output in zip(("ada", "bob"), outputs[1:], strict=True):
        done = re.findall(r"^succeeded \((\w+) (\w+)", output, re.MULTILINE)
        assert done and {robot for _, robot in done} == {name}, output
    assert re.search(r"^faults \d+$", outputs[0], re.MULTILINE), outputs[0]
    assert all(node.returncode == 0 for node in nodes)


@pytest.mark.timeout(60)
def test_a_robot_node_of_no_such_robot_exits_2_naming_the_robots() -> None:
    node = skill_server(str(ROOT / "domains" / "robosim_two_robots"), "--robot", "zed")
    output, _ = node.communicate(timeout=50)
    assert node.returncode == 2
    assert "--robot zed: no such robot in robosim_two_robots; robots: ada, bob" in output
    assert "Traceback" not in output


@pytest.mark.timeout(60)
def test_a_robot_node_of_a_domain_without_a_pyrobosim_world_exits_2() -> None:
    node = skill_server(str(ROOT / "domains" / "fetch_drink"), "--robot", "pr2")
    output, _ = node.communicate(timeout=50)
    assert node.returncode == 2
    assert "--robot pr2: a robot of its own process is for pyrobosim worlds only" in output
