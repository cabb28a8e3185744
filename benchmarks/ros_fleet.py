"""A fleet over ROS 2, a robot process killed: are its orders taken over, and how fast?

Usage::

    .venv/bin/python benchmarks/ros_fleet.py                    # 3 seeds of 30 minutes
    .venv/bin/python benchmarks/ros_fleet.py --seeds 0,1,2,3,4 --minutes 60
    .venv/bin/python benchmarks/ros_fleet.py --quick            # smoke test (tests/benchmarks)

For each seed, ``domains/robosim_hospital`` gets the first ``--minutes`` of its steady
order stream (``orders/steady.yaml``), the doors people close (``events/doors.yaml``)
and faults (``--fail-rate``), and runs twice, as a user runs it:

* **in one process**: ``plan-bridge run ... --orders --events --json``;
* **over ROS 2**: the same with ``--ros`` (a world node and a node per robot, each a
  process of its own, at ``--time-scale``), and one robot's node, drawn from the seed,
  killed with SIGKILL in its first drive after a moment drawn from the seed (between
  20 % and 60 % of the stream).

It prints, per run, the orders by status, any order left open (lost) or done twice,
latency p50/p95, the wall time, and for the kill the seconds from the kill to: the
killed robot's running step ending aborted (if it was in one), the executive's
``gone`` decision (it plans without that robot from then on), and the first of its
orders taken by another robot. Times come from the journal (``time``, the executive's
``time.monotonic()``, the same clock as this script's on Linux).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
HOSPITAL = ROOT / "domains" / "robosim_hospital"
ROBOTS = ("nova", "orla", "pim")


def stream(folder: Path, minutes: float) -> Path:
    """The steady stream's first ``minutes`` as an orders file."""
    import yaml

    data = yaml.safe_load((HOSPITAL / "orders" / "steady.yaml").read_text(encoding="utf-8"))
    for entry in data["streams"]:
        entry["until"] = min(float(entry["until"]), minutes * 60.0)
    path = folder / "orders.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def records(journal: Path) -> list[dict[str, Any]]:
    out = []
    for line in journal.read_text(encoding="utf-8").splitlines():
        try:
            out.append(json.loads(line))
        except ValueError:
            continue  # a line cut by the kill of the run (not here: the robot's)
    return out


def orders_of(journal: Path) -> dict[str, Any]:
    """Each order's final status, orders left open and orders done twice."""
    last: dict[str, dict[str, Any]] = {}
    done: dict[str, int] = {}
    for record in records(journal):
        if record.get("kind") == "order":
            last[record["order"]] = record
            if record["status"] == "done":
                done[record["order"]] = done.get(record["order"], 0) + 1
    final = ("done", "failed", "refused", "cancelled")
    counts: dict[str, int] = {}
    for record in last.values():
        counts[record["status"]] = counts.get(record["status"], 0) + 1
    return {
        "counts": counts,
        "open": sorted(o for o, r in last.items() if r["status"] not in final),
        "done_twice": sorted(o for o, n in done.items() if n > 1),
        "failed": {o: r["reason"] for o, r in last.items() if r["status"] == "failed"},
        "refused": {o: r["reason"] for o, r in last.items() if r["status"] == "refused"},
    }


def run(
    command: list[str], journal: Path, *, kill: tuple[str, float] | None, timeout: float
) -> dict[str, Any]:
    """Run ``command``; with ``kill`` (robot, simulated seconds after the mission began),
    SIGKILL that robot's node then. Its figures (``--json``) and the kill's times."""
    started = time.monotonic()
    process = subprocess.Popen(
        command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    lines: list[str] = []
    reader = threading.Thread(
        target=lambda: lines.extend(process.stderr or ()), daemon=True, name="stderr"
    )
    reader.start()
    killed_at = None
    if kill is not None:
        robot, after_s = kill
        pid = None
        while process.poll() is None and time.monotonic() - started < timeout:
            text = "".join(lines)
            found = re.search(rf"robot node of {robot} .*\(started here, pid (\d+)\)", text)
            began = re.search(r"^plan-bridge run: ", text, re.MULTILINE)
            if found and began:
                pid = int(found[1])
                break
            time.sleep(0.05)
        if pid is None:
            raise SystemExit(f"the robot node of {robot} did not start:\n{''.join(lines)[-3000:]}")
        time.sleep(after_s)
        # Mid-drive: at the robot's next drive from then on (or the end of the stream).
        seen = len(lines)
        while process.poll() is None and not any(
            f"[{robot}]   state /navigate/DRIVE" in line for line in lines[seen:]
        ):
            time.sleep(0.02)
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
            killed_at = time.monotonic()
    out, _ = process.communicate(timeout=timeout)
    reader.join(10)
    if process.returncode not in (0, 1):
        raise SystemExit(f"the run failed ({process.returncode}):\n{''.join(lines)[-3000:]}")
    figures = json.loads(out)
    result: dict[str, Any] = {
        "wall_s": time.monotonic() - started,
        "orders": figures["orders"],
        "tally": orders_of(journal),
    }
    if kill is not None and killed_at is not None:
        result["kill"] = kill_times(journal, kill[0], killed_at)
    return result


def kill_times(journal: Path, robot: str, killed_at: float) -> dict[str, Any]:
    """Seconds from the kill to the robot's step aborting, the ``gone`` decision and its
    first order taken by another robot."""
    held: dict[str, bool] = {}  # order -> the robot had it, unfinished, at the kill
    aborted = gone = taken = None
    for record in records(journal):
        kind, at = record.get("kind"), record.get("time", 0.0)
        if kind == "order" and at < killed_at:
            open_ = record["status"] in ("queued", "assigned", "active")
            held[record["order"]] = open_ and robot in (record.get("robots") or [])
        if at < killed_at:
            continue
        theirs = {order for order, had in held.items() if had}
        words = str(record.get("action", "")).strip("()").split()
        if (
            aborted is None
            and kind == "step_finished"
            and record["outcome"] == "aborted"
            and robot in words[1:2]
        ):
            aborted = at - killed_at
        if gone is None and kind == "executive_decision" and record["decision"] == "gone":
            gone = at - killed_at
        if (
            taken is None
            and kind == "order"
            and record["order"] in theirs
            and record["status"] == "assigned"
            and robot not in record["robots"]
        ):
            taken = at - killed_at
    return {
        "robot": robot,
        "its_orders": sorted(order for order, had in held.items() if had),
        "step_aborted_s": aborted,
        "gone_s": gone,
        "taken_over_s": taken,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated seeds")
    parser.add_argument("--minutes", type=float, default=30.0, help="of the steady stream")
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--time-scale", type=float, default=0.1, help="of the robot nodes")
    parser.add_argument("--quick", action="store_true", help="one seed, 5 minutes")
    parser.add_argument("--json", metavar="FILE", help="write the results as JSON")
    args = parser.parse_args()
    if args.quick:
        args.seeds, args.minutes = "1", 5.0
    seeds = [int(s) for s in args.seeds.split(",")]
    env_note = os.environ.get("ROS_DOMAIN_ID", "0")
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        orders = stream(folder, args.minutes)
        events = HOSPITAL / "events" / "doors.yaml"
        for seed in seeds:
            draw = random.Random(seed)
            robot = draw.choice(ROBOTS)
            at_sim = draw.uniform(0.2, 0.6) * args.minutes * 60.0
            common = [
                sys.executable, "-m", "plan_bridge", "run", str(HOSPITAL),
                "--orders", str(orders), "--events", str(events), "--seed", str(seed),
                "--fail-rate", str(args.fail_rate), "--json",
            ]  # fmt: skip
            local_journal, ros_journal = folder / f"local{seed}.jsonl", folder / f"ros{seed}.jsonl"
            local = run([*common, "--quiet", "--journal", str(local_journal)], local_journal,
                        kill=None, timeout=3600)  # fmt: skip
            ros = run(
                [*common, "--ros", "-v", "--time-scale", str(args.time_scale),
                 "--journal", str(ros_journal)],
                ros_journal,
                kill=(robot, at_sim * args.time_scale),
                timeout=3600,
            )  # fmt: skip
            results.append({"seed": seed, "local": local, "ros": ros, "kill_sim_s": at_sim})
            show(seed, local, ros, at_sim)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1), encoding="utf-8")
    summary(results, args, env_note)


def show(seed: int, local: dict[str, Any], ros: dict[str, Any], at_sim: float) -> None:
    for name, result in (("one process", local), ("over ROS 2", ros)):
        tally, orders = result["tally"], result["orders"]
        print(
            f"seed {seed} {name:11s}: {tally['counts']} open {tally['open']} "
            f"done twice {tally['done_twice']}; latency p50 {orders['latency_p50_s']} s "
            f"p95 {orders['latency_p95_s']} s; wall {result['wall_s']:.1f} s"
        )
    kill = ros.get("kill")
    if kill:
        print(
            f"  killed {kill['robot']} at {at_sim:.0f} simulated s (its orders "
            f"{kill['its_orders']}): step aborted after {fmt(kill['step_aborted_s'])}, "
            f"gone after {fmt(kill['gone_s'])}, an order taken over after "
            f"{fmt(kill['taken_over_s'])}"
        )
    for status in ("failed", "refused"):
        for order, reason in ros["tally"][status].items():
            print(f"  {status} {order}: {reason[:160]}")


def fmt(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds:.2f} s"


def summary(results: list[dict[str, Any]], args: argparse.Namespace, domain: str) -> None:
    def total(where: str, status: str) -> int:
        return sum(r[where]["tally"]["counts"].get(status, 0) for r in results)

    print(
        f"\n{len(results)} seeds, {args.minutes:g} minutes of the steady stream, fail rate "
        f"{args.fail_rate}, time scale {args.time_scale} (ROS_DOMAIN_ID {domain})"
    )
    for where in ("local", "ros"):
        arrived = sum(sum(r[where]["tally"]["counts"].values()) for r in results)
        lost = sum(len(r[where]["tally"]["open"]) for r in results)
        twice = sum(len(r[where]["tally"]["done_twice"]) for r in results)
        p50 = statistics.median(r[where]["orders"]["latency_p50_s"] or 0 for r in results)
        print(
            f"  {'one process' if where == 'local' else 'over ROS 2, a robot killed':27s}: "
            f"{total(where, 'done')}/{arrived} done, {total(where, 'failed')} failed, "
            f"{total(where, 'refused')} refused, {lost} lost, {twice} done twice; "
            f"latency p50 (median of seeds) {p50:.1f} s"
        )
    gone = [r["ros"]["kill"]["gone_s"] for r in results if r["ros"].get("kill")]
    taken = [r["ros"]["kill"]["taken_over_s"] for r in results if r["ros"].get("kill")]
    print(
        f"  kill -> gone: {[fmt(g) for g in gone]}; kill -> an order taken over: "
        f"{[fmt(t) for t in taken]}"
    )


if __name__ == "__main__":
    main()
