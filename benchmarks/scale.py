"""How plan_bridge's cost grows with the building and the fleet: generated buildings.

Usage::

    .venv/bin/python benchmarks/scale.py                  # the default sizes, fail rate 0
    .venv/bin/python benchmarks/scale.py --write          # ... and the table and plot into docs
    .venv/bin/python benchmarks/scale.py --sizes 25x1x2,100x8x16 --fail-rate 0.2 --seeds 1,2
    .venv/bin/python benchmarks/scale.py --baseline 0474866   # with an older plan_bridge too
    .venv/bin/python benchmarks/scale.py --quick          # smoke test (tests/benchmarks)

A size is ``ROOMSxROBOTSxDELIVERIES``. Each run generates the building
(:mod:`plan_bridge.robosim.buildings`: 3 m rooms on a 5 m grid, ``auto`` hallways, a
table at every room's centre, the robots spread over the building, each delivery an
object to a table far from it) and runs ``plan-bridge run BUILDING --json --journal
J`` in a fresh process, as a user would. Per size it prints the time of each phase:

* **load**: pyrobosim's own load of the world file (its cost, not ours);
* **task**: reading the map and making the first task (ours);
* **first plan** and **replans**: planner calls (each ``plan_computed`` of the journal;
  the first plan's time includes starting the planner process when it was not ready);
* **execution**: the run's time outside planning (skills acting in pyrobosim);
* **ours outside**: the process's wall time minus pyrobosim's load minus the run's
  total (starting Python, imports, the map, writing the journal, stopping).

``--baseline REV`` plans the same sizes, in the same run and interleaved, with the
plan_bridge of git revision REV (checked out in a temporary worktree, run with this
environment): ``plan-bridge plan BUILDING --json`` (its problem of every spot of the
building; its *1st plan* is that planning time, its *wall* the whole command). Its
buildings give the robots pyrobosim's ``world_graph`` path planner, which that
revision needs (its wall time then includes building the graph, pyrobosim's cost), and
put the tables against a wall; that revision's runs still fail on them (its drives
depend on pyrobosim's planner, which finds no path into some corners), so only its
planning is compared. ``--write`` puts the table, the plot
(``docs/images/scale.png``) and the command into docs/performance.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from revision import Worktree  # noqa: E402

from plan_bridge.robosim.buildings import Building, write_building  # noqa: E402

DEFAULT_SIZES = "4x1x2,9x1x2,16x1x2,25x1x2,49x1x2,100x1x2,9x3x3,25x4x4,49x6x8,100x8x16"
QUICK_SIZES = "4x1x1,9x2x2"
BASELINE_SIZES = {(4, 1, 2), (9, 1, 2), (16, 1, 2), (25, 1, 2), (9, 3, 3)}
DOC = ROOT / "docs" / "performance.md"
PLOT = ROOT / "docs" / "images" / "scale.png"
BEGIN = "<!-- scale:begin (benchmarks/scale.py --write) -->"
END = "<!-- scale:end -->"


@dataclass(frozen=True)
class Size:
    rooms: int
    robots: int
    deliveries: int

    @classmethod
    def parse(cls, text: str) -> Size:
        try:
            rooms, robots, deliveries = (int(part) for part in text.lower().split("x"))
        except ValueError as exc:
            raise argparse.ArgumentTypeError(
                f"{text!r}: a size is ROOMSxROBOTSxDELIVERIES, e.g. 25x1x2"
            ) from exc
        return cls(rooms, robots, deliveries)

    def __str__(self) -> str:
        return f"{self.rooms}x{self.robots}x{self.deliveries}"


def plan_bridge(args: list[str], source: Path | None = None) -> tuple[dict[str, Any], float]:
    """``plan-bridge ARGS --json`` in a fresh process (``source``: the ``src`` folder of
    another plan_bridge to run): its JSON, and the process's wall time."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    if source is not None:
        env["PYTHONPATH"] = str(source)
    command = [sys.executable, "-m", "plan_bridge", *args, "--json"]
    started = time.perf_counter()
    proc = subprocess.run(
        command, capture_output=True, text=True, timeout=3600, env=env, check=False
    )
    wall = time.perf_counter() - started
    if proc.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(command)} failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout), wall


def run_once(folder: Path, seed: int, fail_rate: float) -> dict[str, Any]:
    """One ``plan-bridge run`` of ``folder`` in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="scale-") as tmp:
        journal = Path(tmp) / "run.jsonl"
        args = ["run", str(folder), "--seed", str(seed), "--fail-rate", str(fail_rate)]
        figures, wall = plan_bridge([*args, "--quiet", "--journal", str(journal)])
        calls = [
            float(event["planning_time_s"])
            for line in journal.read_text(encoding="utf-8").splitlines()
            if line
            for event in [json.loads(line)]
            if event.get("kind") == "plan_computed"
            and "plan reused" not in event.get("reason", "")
            and "from this state before" not in event.get("reason", "")
        ]
    load = float(figures.get("world_load_s", 0.0))
    return {
        "outcome": figures["outcome"],
        "wall_s": wall,
        "load_s": load,
        "task_s": float(figures.get("task_s", 0.0)),
        "first_plan_s": calls[0] if calls else 0.0,
        "replans_s": sum(calls[1:]),
        "replans": len(calls) - 1,
        "planning_s": float(figures["planning_time_s"]),
        "execution_s": float(figures["execution_time_s"]),
        "total_s": float(figures["total_time_s"]),
        "ours_outside_s": wall - load - float(figures["total_time_s"]),
        "steps": int(figures["actions_executed"]),
    }


def measure(
    sizes: list[Size],
    seeds: list[int],
    fail_rate: float,
    baseline: str | None,
    out: Any = print,
) -> dict[str, Any]:
    load_before = os.getloadavg()
    started = time.monotonic()
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="scale-buildings-") as tmp, Worktree(baseline) as old:
        for size in sizes:
            for seed in seeds:
                runs = {"ours": _run(Path(tmp), size, seed, fail_rate, None)}
                if old is not None and (size.rooms, size.robots, size.deliveries) in BASELINE_SIZES:
                    runs["baseline"] = _run(Path(tmp), size, seed, fail_rate, old)
                for who, result in runs.items():
                    rows.append(
                        {"size": str(size), **vars(size), "seed": seed, "who": who, **result}
                    )
                    out(_line(rows[-1]))
    return {
        "fail_rate": fail_rate,
        "seeds": seeds,
        "baseline": baseline,
        "cpus": os.cpu_count(),
        "load_before": [round(x, 2) for x in load_before],
        "load_after": [round(x, 2) for x in os.getloadavg()],
        "wall_s": round(time.monotonic() - started, 1),
        "rows": rows,
    }


def plan_once(folder: Path, source: Path) -> dict[str, Any]:
    """``plan-bridge plan`` of ``folder`` by the plan_bridge of ``source`` (a fresh
    process): its planning time, and the process's wall time."""
    figures, wall = plan_bridge(["plan", str(folder)], source)
    planning = float(figures["planning_time_s"])
    row = dict.fromkeys(("load_s", "task_s", "replans_s", "execution_s", "ours_outside_s"), 0.0)
    return {
        **row,
        "outcome": "succeeded" if figures["status"] == "solved" else figures["status"],
        "wall_s": wall,
        "first_plan_s": planning,
        "planning_s": planning,
        "total_s": planning,
        "replans": 0,
        "steps": int(figures["plan_length"]),
    }


def _run(tmp: Path, size: Size, seed: int, fail_rate: float, old: Path | None) -> dict[str, Any]:
    # The baseline's skills need pyrobosim's world graph, and its spots (at a room's
    # centre for auto hallways) a room's centre free of furniture: its buildings have
    # both; ours have neither (the harder case).
    planner = "world_graph" if old is not None else "none"
    spec = Building(
        size.rooms,
        size.robots,
        size.deliveries,
        seed=seed,
        planner=planner,
        table_at_centre=old is None,
    )
    folder = write_building(tmp / f"{size}-{seed}-{planner}", spec)
    if old is not None:
        return plan_once(folder, old / "src")
    return run_once(folder, seed, fail_rate)


COLUMNS = (
    ("load_s", "load"),
    ("task_s", "task"),
    ("first_plan_s", "1st plan"),
    ("replans_s", "replans"),
    ("execution_s", "exec"),
    ("ours_outside_s", "ours out"),
    ("wall_s", "wall"),
)


def _line(row: dict[str, Any]) -> str:
    cells = " ".join(f"{label} {row[key]:7.2f}" for key, label in COLUMNS)
    return (
        f"{row['size']:>10} seed {row['seed']} {row['who']:<8} {row['outcome']:<9} "
        f"{cells} ({row['replans']} replans, {row['steps']} steps)"
    )


def table(result: dict[str, Any]) -> str:
    """The markdown table: per size and planner, the median of each phase (seconds)."""
    head = "| rooms x robots x deliveries | run | goal | " + " | ".join(
        label for _, label in COLUMNS
    )
    lines = [head + " |", "|" + "---|" * (len(COLUMNS) + 3)]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in result["rows"]:
        groups.setdefault((row["size"], row["who"]), []).append(row)
    for (size, who), rows in groups.items():
        reached = sum(r["outcome"] == "succeeded" for r in rows)
        if who == "baseline":  # `plan` of the older revision: planning only
            cells = " | ".join(
                f"{statistics.median(r[key] for r in rows):.2f}"
                if key in ("first_plan_s", "wall_s")
                else "-"
                for key, _ in COLUMNS
            )
            run = f"{result.get('baseline')} (`plan`)"
            lines.append(f"| {size} | {run} | {reached}/{len(rows)} planned | {cells} |")
            continue
        cells = " | ".join(f"{statistics.median(r[key] for r in rows):.2f}" for key, _ in COLUMNS)
        lines.append(f"| {size} | {who} | {reached}/{len(rows)} | {cells} |")
    return "\n".join(lines)


def plot(result: dict[str, Any], path: Path) -> None:
    """Planning and pyrobosim's load against the number of rooms, one robot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (single, fleet) = plt.subplots(1, 2, figsize=(10, 4))
    lines = (
        ("ours", "planning_s", "-", "planning"),
        ("ours", "load_s", "-", "pyrobosim's load"),
        ("baseline", "planning_s", "--", f"planning, {result.get('baseline')}"),
    )
    for who, key, style, label in lines:
        rows = [r for r in result["rows"] if r["who"] == who and r["robots"] == 1]
        rooms = sorted({r["rooms"] for r in rows})
        if rooms:
            medians = [statistics.median(r[key] for r in rows if r["rooms"] == n) for n in rooms]
            single.plot(rooms, medians, style, marker="o", label=label)
    single.set(xlabel="rooms (1 robot, 2 deliveries)", ylabel="seconds", yscale="log")
    single.legend(fontsize=8)
    fleets = [r for r in result["rows"] if r["who"] == "ours" and r["robots"] > 1]
    labels = sorted({r["size"] for r in fleets}, key=lambda s: [int(p) for p in s.split("x")])
    for key, label in (("first_plan_s", "first plan"), ("planning_s", "all planning")):
        medians = [statistics.median(r[key] for r in fleets if r["size"] == s) for s in labels]
        fleet.plot(labels, medians, marker="o", label=label)
    fleet.set(xlabel="rooms x robots x deliveries", ylabel="seconds")
    fleet.legend(fontsize=8)
    fig.suptitle("plan_bridge on generated buildings (benchmarks/scale.py)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_docs(result: dict[str, Any], command: str) -> None:
    plot(result, PLOT)
    text = DOC.read_text(encoding="utf-8")
    body = "\n".join(
        [
            BEGIN,
            "```sh",
            command,
            "```",
            "",
            f"2 CPUs, load average {result['load_before'][0]} before and "
            f"{result['load_after'][0]} after; fail rate {result['fail_rate']}, seeds "
            f"{', '.join(map(str, result['seeds']))}; medians, seconds. *load* is "
            "pyrobosim's own load of the world file; *ours out* is the process's wall "
            "time minus that load and the run's total.",
            "",
            table(result),
            "",
            f"![planning time against the building's size]({PLOT.relative_to(DOC.parent)})",
            END,
        ]
    )
    if BEGIN in text and END in text:
        text = text[: text.index(BEGIN)] + body + text[text.index(END) + len(END) :]
    else:
        text = text.rstrip() + "\n\n## Scaling with the building and the fleet\n\n" + body + "\n"
    DOC.write_text(text, encoding="utf-8")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default=DEFAULT_SIZES, help="ROOMSxROBOTSxDELIVERIES,...")
    parser.add_argument("--seeds", default="1", help="comma-separated seeds")
    parser.add_argument("--fail-rate", type=float, default=0.0)
    parser.add_argument("--baseline", help="a git revision of plan_bridge to compare with")
    parser.add_argument("--json", type=Path, help="write every run's numbers here")
    parser.add_argument("--write", action="store_true", help="update docs/performance.md")
    parser.add_argument("--quick", action="store_true", help="two small sizes (a smoke test)")
    parser.add_argument(
        "--from-json", type=Path, help="no runs: the results of an earlier --json (for --write)"
    )
    args = parser.parse_args()
    sizes = [Size.parse(s) for s in (QUICK_SIZES if args.quick else args.sizes).split(",")]
    seeds = [int(s) for s in args.seeds.split(",")]
    if args.from_json is not None:
        result = json.loads(args.from_json.read_text(encoding="utf-8"))
    else:
        result = measure(sizes, seeds, args.fail_rate, args.baseline)
        result["command"] = "python benchmarks/scale.py " + " ".join(sys.argv[1:])
    print()
    print(table(result))
    print(
        f"\nwall {result['wall_s']} s, load average {result['load_before']} -> {result['load_after']}"
    )
    if args.json is not None:
        args.json.write_text(json.dumps(result, indent=1), encoding="utf-8")
    if args.write:
        write_docs(result, result.get("command", "python benchmarks/scale.py"))
        print(f"wrote {DOC.relative_to(ROOT)} and {PLOT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
