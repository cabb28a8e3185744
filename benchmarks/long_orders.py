"""A day of orders: memory, journal and resume over hours of simulated work.

Usage::

    .venv/bin/python benchmarks/long_orders.py                 # 8 h, 3 robots, ~200 orders
    .venv/bin/python benchmarks/long_orders.py --hours 1 --kills 2
    .venv/bin/python benchmarks/long_orders.py --quick         # smoke test (tests/benchmarks)

A generated building (:mod:`plan_bridge.robosim.buildings`: 9 rooms, 3 robots, a
charger, parcels on tables) gets a Poisson stream of delivery orders (a parcel to a
table, ``--rate`` an hour for ``--hours`` simulated hours), hallways that people close
and open again at seeded moments, and faults (``--fail-rate``). One ``plan-bridge run
--orders --events --journal`` runs it in a fresh process, as a user would, while this
script samples the process's resident memory (RSS) every ``--sample`` seconds. It
prints:

* the orders by status, latency p50/p95 and orders done per simulated hour;
* **memory**: RSS after the warm-up (the first ``--warm-up`` share of the run) and at
  its highest and at the end, and the growth after the warm-up;
* **journal**: bytes per executed action, ``structure`` records per plan machine, and
  the biggest kinds of records;
* **resume**: ``--kills N`` runs again killed with SIGKILL at N seeded moments, each
  resumed to its end (``plan-bridge run --resume``), and compares each order's final
  status with the uninterrupted run's (lost or repeated orders would differ).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "plan_bridge", *args]


def build(folder: Path, args: argparse.Namespace) -> tuple[Path, Path]:
    """The building, its orders file and its events file."""
    import yaml

    subprocess.run(
        [
            sys.executable, "-m", "plan_bridge.robosim.buildings", str(folder),
            "--rooms", str(args.rooms), "--robots", str(args.robots),
            "--deliveries", str(args.parcels), "--seed", str(args.seed),
        ],
        check=True,
    )  # fmt: skip
    world = yaml.safe_load((folder / "world.yaml").read_text(encoding="utf-8"))
    tables = [f"{loc['name']}_tabletop" for loc in world["locations"] if loc["category"] == "table"]
    parcels = [obj["name"] for obj in world["objects"]]
    goals = [f"(At {parcel} {table})" for parcel in parcels for table in tables]
    seconds = args.hours * 3600.0
    orders = folder / "orders.yaml"
    orders.write_text(
        yaml.safe_dump(
            {
                "streams": [
                    {
                        "rate_per_hour": args.rate,
                        "until": seconds,
                        "goals": goals,
                        "id": "day",
                        "within": 900,
                    }
                ]
            }
        ),
        encoding="utf-8",
    )
    halls = [f"hall_{hall['room_start']}_{hall['room_end']}" for hall in world.get("hallways", [])]
    rng = random.Random(args.seed)
    events = []
    for hour in range(int(args.hours)):
        hall = rng.choice(halls)
        start = hour * 3600.0 + 600
        events.append({"at": [start, start + 1200], "close": hall})
        events.append({"at": [start + 1500, start + 2400], "open": hall})
    events_file = folder / "events.yaml"
    events_file.write_text(yaml.safe_dump(events), encoding="utf-8")
    return orders, events_file


def rss_mb(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def run(
    folder: Path, orders: Path, events: Path, journal: Path, args: argparse.Namespace,
    *, kill_after: float | None = None, sample: float = 1.0,
) -> dict[str, Any]:  # fmt: skip
    """One journaled run; its figures (``--json``), wall time and RSS samples; with
    ``kill_after`` (wall seconds after the journal appeared, i.e. the mission began),
    killed then and resumed."""
    command = _cli(
        "run", str(folder), "--orders", str(orders), "--events", str(events),
        "--seed", str(args.seed), "--fail-rate", str(args.fail_rate),
        "--journal", str(journal), "--quiet", "--json",
    )  # fmt: skip
    started = time.monotonic()
    # Files, not pipes: a day's --json is bigger than a pipe's buffer.
    out_file = journal.with_suffix(".out")
    err_file = journal.with_suffix(".err")
    with out_file.open("w") as out_stream, err_file.open("w") as err_stream:
        process = subprocess.Popen(command, stdout=out_stream, stderr=err_stream, text=True)
    samples: list[tuple[float, float]] = []
    killed = False
    began: float | None = None  # when the journal appeared: the mission began
    while process.poll() is None:
        now = time.monotonic() - started
        mb = rss_mb(process.pid)
        if mb is not None:
            samples.append((now, mb))
        if began is None and journal.exists():
            began = now
        if kill_after is not None and began is not None and now - began >= kill_after:
            os.kill(process.pid, signal.SIGKILL)
            killed = True
            break
        time.sleep(sample)
    process.wait(timeout=60)
    out, err = out_file.read_text(), err_file.read_text()
    if killed:
        resumed = subprocess.run(
            _cli("run", "--resume", str(journal), "--quiet", "--json"),
            capture_output=True, text=True, timeout=4 * 3600, check=False,
        )  # fmt: skip
        out, err = resumed.stdout, resumed.stderr
        if resumed.returncode not in (0, 1):
            raise SystemExit(f"the resumed run failed ({resumed.returncode}):\n{err[-3000:]}")
    elif process.returncode not in (0, 1):
        raise SystemExit(f"the run failed ({process.returncode}):\n{err[-3000:]}")
    figures = json.loads(out)
    return {
        "mission_s": (time.monotonic() - started) - (began or 0.0),
        "figures": figures,
        "wall_s": time.monotonic() - started,
        "samples": samples,
        "killed": killed,
    }


def journal_figures(journal: Path, actions: int) -> dict[str, Any]:
    sizes: collections.Counter[str] = collections.Counter()
    counts: collections.Counter[str] = collections.Counter()
    statuses: dict[str, str] = {}
    plans = 0
    with journal.open(encoding="utf-8") as lines:
        for line in lines:
            record = json.loads(line)
            kind = record.get("kind", "?")
            sizes[kind] += len(line.encode())
            counts[kind] += 1
            if kind == "order":
                statuses[record["order"]] = record["status"]
            elif kind == "container_started" and record.get("path", "").endswith("/PLAN"):
                plans += 1
    total = sum(sizes.values())
    return {
        "bytes": total,
        "bytes_per_action": total / max(1, actions),
        "structures": counts["structure"],
        "plan_machines": plans,
        "biggest": [(k, sizes[k], counts[k]) for k, _ in sizes.most_common(6)],
        "statuses": statuses,
    }


def memory(samples: list[tuple[float, float]], warm_up: float) -> dict[str, Any]:
    """RSS after the warm-up, highest, at the end, the growth after the warm-up, and
    the RSS at each tenth of the run (``by_tenth``: flat, or growing all along?)."""
    if not samples:
        return {}
    end = samples[-1][0]
    after = [mb for t, mb in samples if t >= warm_up * end] or [samples[-1][1]]
    by_tenth = [
        round(next((mb for t, mb in samples if t >= tenth / 10 * end), samples[-1][1]), 1)
        for tenth in range(1, 11)
    ]
    return {
        "after_warm_up_mb": after[0],
        "max_mb": max(mb for _, mb in samples),
        "end_mb": samples[-1][1],
        "growth_mb": max(after) - after[0],
        "by_tenth": by_tenth,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hours", type=float, default=8.0)
    parser.add_argument("--rate", type=float, default=25.0, help="orders an hour")
    parser.add_argument("--rooms", type=int, default=9)
    parser.add_argument("--robots", type=int, default=3)
    parser.add_argument("--parcels", type=int, default=6)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument(
        "--kills", type=int, help="killed-and-resumed runs (default 1; 0 with --quick)"
    )
    parser.add_argument("--warm-up", type=float, default=0.1, help="share of the run")
    parser.add_argument("--sample", type=float, default=1.0, help="seconds between samples")
    parser.add_argument("--quick", action="store_true", help="20 simulated minutes, 4 rooms")
    parser.add_argument("--json", metavar="FILE", help="write every figure to FILE")
    args = parser.parse_args()
    if args.quick:
        args.hours, args.rooms, args.robots, args.sample = 1 / 3, 4, 2, 0.2
    if args.kills is None:
        args.kills = 0 if args.quick else 1
    with tempfile.TemporaryDirectory(prefix="long-orders-") as tmp:
        folder = Path(tmp) / "building"
        orders, events = build(folder, args)
        print(
            f"{args.rooms} rooms, {args.robots} robots, {args.rate:g} orders/h for "
            f"{args.hours:g} simulated h, fail rate {args.fail_rate}, seed {args.seed}",
            flush=True,
        )
        whole = run(folder, orders, events, Path(tmp) / "whole.jsonl", args, sample=args.sample)
        figures = whole["figures"]
        journal = journal_figures(Path(tmp) / "whole.jsonl", figures["actions_executed"])
        mem = memory(whole["samples"], args.warm_up)
        result: dict[str, Any] = {
            "orders": figures["orders"],
            "actions": figures["actions_executed"],
            "sim_time_s": figures.get("sim_time_s"),
            "wall_s": round(whole["wall_s"], 1),
            "memory": mem,
            "journal": {k: v for k, v in journal.items() if k != "statuses"},
            "resumes": [],
        }
        o = figures["orders"]
        print(
            f"orders: {o['orders']} arrived, {o['done']} done, {o['failed']} failed, "
            f"{o['refused']} refused, {o['late']} late; latency p50 {o['latency_p50_s']} s, "
            f"p95 {o['latency_p95_s']} s; {o['orders_per_hour']} done per simulated hour"
        )
        print(
            f"run: {figures['actions_executed']} actions, {figures['planner_calls']} planner "
            f"calls, planning {figures['planning_time_s']:.1f} s, simulated "
            f"{figures.get('sim_time_s', 0) / 3600:.2f} h in {whole['wall_s']:.0f} s wall"
        )
        if mem:
            print(
                f"memory (RSS): {mem['after_warm_up_mb']:.0f} MB after warm-up, highest "
                f"{mem['max_mb']:.0f} MB, end {mem['end_mb']:.0f} MB: growth "
                f"{mem['growth_mb']:.1f} MB after warm-up; by tenths of the run: "
                + " ".join(f"{mb:.0f}" for mb in mem["by_tenth"])
            )
        print(
            f"journal: {journal['bytes'] / 2**20:.1f} MB, "
            f"{journal['bytes_per_action'] / 1024:.1f} KB per action; "
            f"{journal['structures']} structure records for {journal['plan_machines']} plan "
            f"machines; biggest: "
            + ", ".join(f"{k} {b / 2**20:.1f} MB ({n})" for k, b, n in journal["biggest"])
        )
        rng = random.Random(args.seed)
        for number in range(args.kills):
            at = rng.uniform(0.1, 0.9) * whole["mission_s"]
            path = Path(tmp) / f"killed-{number}.jsonl"
            again = run(folder, orders, events, path, args, kill_after=at, sample=args.sample)
            statuses = journal_figures(path, again["figures"]["actions_executed"])["statuses"]
            same = statuses == journal["statuses"]
            differ = sorted(k for k in statuses.keys() | journal["statuses"].keys()
                            if statuses.get(k) != journal["statuses"].get(k))  # fmt: skip
            result["resumes"].append(
                {"killed_into_mission_s": round(at, 1), "same_orders": same, "differ": differ}
            )
            print(
                f"resume: killed {at:.0f} s (wall) into the mission, resumed: "
                + ("the same orders done, failed and refused" if same else f"differ: {differ}")
            )
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
