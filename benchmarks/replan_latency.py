"""Replanning latency of the shipped missions: the warm path against Fast Downward.

Usage::

    .venv/bin/python benchmarks/replan_latency.py                 # 5 seeds, 8 missions
    .venv/bin/python benchmarks/replan_latency.py --baseline 0474866  # temporal: vs an old revision
    .venv/bin/python benchmarks/replan_latency.py --seeds 10 --json latency.json
    .venv/bin/python benchmarks/replan_latency.py --quick         # smoke test

Each run is ``plan-bridge run domains/MISSION --seed N --fail-rate 0.3 --json
--journal FILE --planner PLANNER``, a fresh process as a user would start it (the
issue's measurement). Per mission and planner it reports:

* **call**: the time of one planner call (each ``plan_computed`` event of the
  journal that called a planner: its ``planning_time_s``), p50 and p95;
* **fail->next**: the time from a step's failure (its ``step_finished`` event with
  an outcome other than ``succeeded``) to the start of the next step (the next step
  state's ``state_entered``): what the robot waits for, repair or replan included;
* the same two numbers for ``--planner fast-downward``, the planner of every call a
  fresh Fast Downward process (translate, then search), measured in the same run
  with the runs interleaved (same seeds, same load), and their ratio.

``auto`` is the default planner: for the classical missions it is the warm search in
the planner worker (:mod:`plan_bridge.planning.warm`), for the temporal ones (timed
courier and the pyrobosim missions) Kairos in the planner worker without
unified-planning's round trip (:mod:`plan_bridge.planning.kairos_direct`); Fast
Downward does not plan those, so ``--baseline REV`` runs them with an older revision
of plan_bridge too, in the same run. The last line pools every call of every mission
per planner (the target: p50 <= 50 ms, p95 <= 150 ms).
The load average is printed before and after: other work on the machine slows both
planners.

``--ipc N`` adds the IPC problems of ../shared/pddl-bench, planned in this process
by ``auto`` as an execution uses it (the warm search first, Fast Downward after its
budget) and by Fast Downward alone, N trials each, interleaved: what the warm path
costs where Fast Downward is the stronger planner.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
MISSIONS = ("fetch_drink", "door_opening", "table_clearing", "recharge")
#: Temporal missions (durative actions; Fast Downward does not plan them): planned by
#: ``auto`` (Kairos in the planner process), compared with ``--baseline REV``.
TEMPORAL = ("timed_courier", "robosim_fetch", "robosim_house", "robosim_two_robots")
PLANNERS = ("auto", "fast-downward")
FRESH = "fast-downward"
_STEP_STATE = re.compile(r"^/ROOT/PLAN/\d+_[^/]*$")


def percentile(values: list[float], share: float) -> float:
    """The ``share`` quantile (nearest rank) of ``values``; 0 for none."""
    if not values:
        return 0.0
    ordered = sorted(values)
    rank = min(len(ordered) - 1, max(0, math.ceil(share * len(ordered)) - 1))
    return ordered[rank]


def journal_times(lines: list[dict[str, Any]]) -> tuple[list[float], list[float]]:
    """(planner call times, failure -> next step start times) of one run's journal."""
    calls = [
        float(event["planning_time_s"])
        for event in lines
        if event["kind"] == "plan_computed"
        and "plan reused" not in event.get("reason", "")
        and "from this state before" not in event.get("reason", "")
    ]
    waits: list[float] = []
    failed_at: float | None = None
    for event in lines:
        if event["kind"] == "step_finished" and event.get("outcome") != "succeeded":
            failed_at = float(event["time"])
        elif (
            failed_at is not None
            and event["kind"] == "state_entered"
            and _STEP_STATE.match(event.get("path", ""))
        ):
            waits.append(float(event["time"]) - failed_at)
            failed_at = None
    return calls, waits


def run_mission(
    mission: str, planner: str, seed: int, fail_rate: float, source: Path | None = None
) -> dict[str, Any]:
    """One ``plan-bridge run`` in a fresh process: its JSON summary and journal times
    (``source``: the ``src`` folder of another revision's plan_bridge, run instead)."""
    with tempfile.TemporaryDirectory(prefix="replan-latency-") as tmp:
        journal = Path(tmp) / "journal.jsonl"
        command = [
            str(Path(sys.executable).with_name("plan-bridge")),
            "run",
            str(ROOT / "domains" / mission),
            "--seed",
            str(seed),
            "--fail-rate",
            str(fail_rate),
            "--planner",
            planner,
            "--json",
            "--journal",
            str(journal),
        ]
        env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        if source is not None or not Path(command[0]).exists():
            command[:1] = [sys.executable, "-m", "plan_bridge"]
        if source is not None:
            env["PYTHONPATH"] = str(source)
        proc = subprocess.run(
            command, cwd=ROOT, capture_output=True, text=True, timeout=600, check=False, env=env
        )
        if proc.returncode not in (0, 1):  # 1: the mission did not reach its goal
            raise RuntimeError(f"{' '.join(command)} failed:\n{proc.stderr[-2000:]}")
        summary = json.loads(proc.stdout)
        events = [json.loads(line) for line in journal.read_text().splitlines() if line]
    calls, waits = journal_times(events)
    return {
        "mission": mission,
        "planner": planner if source is None else f"{planner}@baseline",
        "seed": seed,
        "outcome": summary["outcome"],
        "planner_calls": summary["planner_calls"],
        "actions_executed": summary["actions_executed"],
        "planning_time_s": summary["planning_time_s"],
        "planners_won": summary.get("planners_won", {}),
        "calls_s": calls,
        "fail_to_next_s": waits,
    }


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    calls = [c for run in runs for c in run["calls_s"]]
    waits = [w for run in runs for w in run["fail_to_next_s"]]
    per_run = [
        run["planning_time_s"] / run["planner_calls"] for run in runs if run["planner_calls"]
    ]
    won: dict[str, int] = {}
    for run in runs:
        for name, count in run["planners_won"].items():
            won[name] = won.get(name, 0) + count
    return {
        "runs": len(runs),
        "calls": len(calls),
        "call_p50_s": percentile(calls, 0.5),
        "call_p95_s": percentile(calls, 0.95),
        "failures": len(waits),
        "fail_to_next_p50_s": percentile(waits, 0.5),
        "fail_to_next_p95_s": percentile(waits, 0.95),
        "per_run_call_median_s": statistics.median(per_run) if per_run else 0.0,
        "goal_reached": sum(run["outcome"] == "succeeded" for run in runs),
        "actions_per_run": statistics.mean(run["actions_executed"] for run in runs)
        if runs
        else 0.0,
        "planners_won": won,
    }


def measure(
    missions: tuple[str, ...],
    planners: tuple[str, ...],
    seeds: int,
    fail_rate: float,
    baseline: str | None = None,
) -> dict[str, Any]:
    from revision import Worktree

    load_before = os.getloadavg()
    started = time.monotonic()
    runs: list[dict[str, Any]] = []
    with Worktree(baseline) as old:
        for mission in missions:
            chosen = ("auto",) if mission in TEMPORAL else planners
            for seed in range(1, seeds + 1):
                for planner in chosen:  # interleaved: the planners see the same load
                    runs.append(run_mission(mission, planner, seed, fail_rate))
                if old is not None and mission in TEMPORAL:
                    runs.append(run_mission(mission, "auto", seed, fail_rate, old / "src"))
    labels = list(dict.fromkeys(run["planner"] for run in runs))
    rows = []
    for mission in (*missions, "all"):
        for label in labels:
            chosen_runs = [
                r for r in runs if r["planner"] == label and mission in ("all", r["mission"])
            ]
            if chosen_runs:
                rows.append({"mission": mission, "planner": label, **summarise(chosen_runs)})
    return {
        "fail_rate": fail_rate,
        "seeds": seeds,
        "baseline": baseline,
        "cpus": os.cpu_count(),
        "load_before": [round(x, 2) for x in load_before],
        "load_after": [round(x, 2) for x in os.getloadavg()],
        "wall_s": round(time.monotonic() - started, 1),
        "rows": rows,
        "runs": runs,
    }


def ipc_section(folder: Path, trials: int) -> list[dict[str, Any]]:
    """Every IPC problem UP parses, planned in this process by ``auto`` as an execution
    uses it (warm search first) and by Fast Downward, both through one warm worker
    pool, interleaved; a fresh task per trial (nothing remembered between trials)."""
    from plan_bridge.planning.registry import get_planner

    fresh = get_planner(FRESH)
    fresh.warm_up()
    rows = []
    for domain in sorted(p for p in folder.iterdir() if (p / "domain.pddl").exists()):
        for problem in sorted(domain.glob("*.pddl")):
            if problem.name != "domain.pddl":
                row = _ipc_problem(domain, problem, trials, fresh)
                if row is not None:
                    rows.append(row)
    return rows


def _ipc_problem(domain: Path, problem: Path, trials: int, fresh: Any) -> dict[str, Any] | None:
    import warnings

    from plan_bridge.pddl.task import load_task
    from plan_bridge.planning.engines import AutoPlanner

    times: dict[str, list[float]] = {"auto": [], FRESH: []}
    won: set[str] = set()
    lengths: dict[str, int] = {}
    for _ in range(trials):
        for name, samples in times.items():
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    task = load_task(domain / "domain.pddl", problem)
            except Exception:
                return None  # not parsed by UP (storage)
            planner = AutoPlanner(warm=True) if name == "auto" else fresh
            result = planner.solve(task, timeout=60)
            samples.append(result.planning_time_s)
            lengths[name] = len(result.actions)
            if name == "auto":
                won.add(result.planner)
    auto, direct = statistics.median(times["auto"]), statistics.median(times[FRESH])
    return {
        "problem": f"{domain.name}/{problem.stem}",
        "auto_s": auto,
        "fast_downward_s": direct,
        "ratio": auto / direct if direct else 0.0,
        "won": sorted(won),
        "length_auto": lengths.get("auto", 0),
        "length_fast_downward": lengths.get(FRESH, 0),
    }


def print_ipc(rows: list[dict[str, Any]], out: Any = print) -> None:
    out(f"{'IPC problem':<34}{'auto s':>9}{'FD s':>9}{'auto/FD':>9}  won by       length")
    for row in rows:
        out(
            f"{row['problem']:<34}{row['auto_s']:>9.3f}{row['fast_downward_s']:>9.3f}"
            f"{row['ratio']:>9.2f}  {','.join(row['won']):<12} "
            f"{row['length_auto']} vs {row['length_fast_downward']}"
        )
    if rows:
        ratios = [row["ratio"] for row in rows]
        out(f"median auto/FD {statistics.median(ratios):.2f}, max {max(ratios):.2f}")


def _ms(seconds: float) -> str:
    return f"{seconds * 1000:7.1f}"


def print_table(results: dict[str, Any], out: Any = print) -> None:
    out(
        f"replan latency: {results['seeds']} seeds, fail rate {results['fail_rate']:g}, "
        f"{results['cpus']} CPUs, load {results['load_before']} -> {results['load_after']}"
    )
    out(
        f"{'mission':<15}{'planner':<15}{'calls':>6}{'call p50':>10}{'call p95':>10}"
        f"{'fails':>6}{'f->n p50':>10}{'f->n p95':>10}{'FD/this p50':>13}{'f->n ratio':>12}"
    )
    fresh = {row["mission"]: row for row in results["rows"] if row["planner"] == FRESH}
    older = {row["mission"]: row for row in results["rows"] if row["planner"].endswith("@baseline")}
    for row in results["rows"]:
        base = fresh.get(row["mission"]) if row["mission"] not in TEMPORAL else None
        base = base or (older.get(row["mission"]) if row["mission"] in TEMPORAL else None)
        ratio = wait_ratio = "-"
        if base is not None and base is not row and row["call_p50_s"] > 0:
            ratio = f"x{base['call_p50_s'] / row['call_p50_s']:.1f}"
            if row["fail_to_next_p50_s"] > 0:
                wait_ratio = f"x{base['fail_to_next_p50_s'] / row['fail_to_next_p50_s']:.1f}"
        out(
            f"{row['mission']:<15}{row['planner']:<15}{row['calls']:>6}"
            f"{_ms(row['call_p50_s']):>10}{_ms(row['call_p95_s']):>10}{row['failures']:>6}"
            f"{_ms(row['fail_to_next_p50_s']):>10}{_ms(row['fail_to_next_p95_s']):>10}"
            f"{ratio:>13}{wait_ratio:>12}"
        )
    out(
        "times in ms; FD/this: a fresh Fast Downward process per call (for temporal "
        "missions: the baseline revision), same run, over this"
    )
    for row in results["rows"]:
        if row["mission"] == "all":
            won = ", ".join(f"{k} {v}" for k, v in sorted(row["planners_won"].items()))
            out(
                f"  {row['planner']}: median over runs of planning time / calls "
                f"{row['per_run_call_median_s'] * 1000:.1f} ms; plans by {won}; goal "
                f"reached in {row['goal_reached']}/{row['runs']} runs, "
                f"{row['actions_per_run']:.1f} actions executed per run"
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds 1..N per mission")
    parser.add_argument("--missions", default=",".join((*MISSIONS, *TEMPORAL)))
    parser.add_argument("--planners", default=",".join(PLANNERS))
    parser.add_argument("--fail-rate", type=float, default=0.3)
    parser.add_argument("--quick", action="store_true", help="1 seed of fetch_drink")
    parser.add_argument(
        "--baseline", metavar="REV", help="also run the temporal missions with revision REV"
    )
    parser.add_argument("--json", metavar="FILE", help="write the results as JSON")
    parser.add_argument(
        "--ipc",
        type=int,
        default=0,
        metavar="TRIALS",
        help="also plan every IPC problem of ../shared/pddl-bench (auto vs Fast Downward)",
    )
    args = parser.parse_args(argv)
    missions = tuple(m for m in args.missions.split(",") if m)
    seeds = args.seeds
    if args.quick:
        missions, seeds = ("fetch_drink",), 1
    results = measure(
        missions, tuple(args.planners.split(",")), seeds, args.fail_rate, args.baseline
    )
    print_table(results)
    if args.ipc:
        sys.path.insert(0, str(ROOT / "src"))
        results["ipc"] = ipc_section(ROOT.parent / "shared" / "pddl-bench", args.ipc)
        print_ipc(results["ipc"])
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
