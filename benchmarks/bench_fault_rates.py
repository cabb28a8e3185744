"""Goal-reached rate of ``plan-bridge run`` with injected failures, over many seeds.

Usage::

    .venv/bin/python benchmarks/bench_fault_rates.py                 # 10 seeds x every problem
    .venv/bin/python benchmarks/bench_fault_rates.py --seeds 3 --fail-rate 0.3
    .venv/bin/python benchmarks/bench_fault_rates.py --quick         # smallest problem per domain, 3 seeds
    .venv/bin/python benchmarks/bench_fault_rates.py --json rates.json

Each run is ``plan-bridge run DOMAIN.pddl --problem P --fail-rate R --seed N`` done in
process: symbolic skills in a simulated world that makes each action fail (no effect)
with probability R, and the Executive with the default policy (retry once, continue,
repair, replan; at most ``--max-replans`` planner calls after the first). The table
gives, per problem, the goal-reached rate, the failed actions and the recoveries.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
BENCH = (ROOT / ".." / "shared" / "pddl-bench").resolve()


def problems(quick: bool) -> list[tuple[Path, Path]]:
    from plan_bridge.errors import PddlError
    from plan_bridge.pddl.task import load_task

    pairs = []
    for folder in sorted(p for p in BENCH.iterdir() if p.is_dir()):
        domain = folder / "domain.pddl"
        found = sorted(p for p in folder.glob("*.pddl") if p.name != "domain.pddl")
        try:
            load_task(domain, found[0])
        except PddlError:
            print(f"skipped {folder.name}: not parsed by unified-planning", file=sys.stderr)
            continue
        if quick:
            found = [min(found, key=lambda p: p.stat().st_size)]
        pairs.extend((domain, p) for p in found)
    return pairs


def run_once(
    domain: Path, problem: Path, seed: int, fail_rate: float, max_replans: int, planner: Any
) -> dict[str, Any]:
    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.missions.mission import load_target

    target = load_target(domain, problem)
    setup = target.setup(seed=seed, fail_rate=fail_rate)
    executive = Executive(
        target.task,
        setup.skills,
        planner,
        policy=replace(ReplanPolicy(), max_replans=max_replans),
    )
    executive.execute()
    report = executive.report
    return {
        "reached": report.goal_reached and setup.world.goal_reached(),
        "failed": report.actions_failed,
        "retries": report.retries,
        "continues": report.continues,
        "repairs": report.repairs,
        "replans": report.replans,
        "planner_calls": report.planner_calls,
        "plan_length": len(report.executed),
        "total_s": report.total_time_s,
        "explanation": "" if report.goal_reached else report.explanation,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=None, help="seeds per problem (default 10)")
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--max-replans", type=int, default=10)
    parser.add_argument("--quick", action="store_true", help="smallest problem per domain")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    seeds = args.seeds or (3 if args.quick else 10)

    from plan_bridge.planning.planner import get_planner

    planner = get_planner("fast-downward")
    planner.warm_up()
    started = time.perf_counter()
    rows = []
    for domain, problem in problems(args.quick):
        name = f"{problem.parent.name}/{problem.stem}"
        runs = []
        for seed in range(seeds):
            runs.append(run_once(domain, problem, seed, args.fail_rate, args.max_replans, planner))
        reached = sum(r["reached"] for r in runs)
        row = {
            "problem": name,
            "runs": len(runs),
            "reached": reached,
            "rate": reached / len(runs),
            "executed_median": statistics.median(r["plan_length"] for r in runs),
            "failed_mean": statistics.mean(r["failed"] for r in runs),
            "retries_mean": statistics.mean(r["retries"] for r in runs),
            "continues_mean": statistics.mean(r["continues"] for r in runs),
            "repairs_mean": statistics.mean(r["repairs"] for r in runs),
            "replans_mean": statistics.mean(r["replans"] for r in runs),
            "time_median_s": statistics.median(r["total_s"] for r in runs),
            "why_missed": sorted({r["explanation"][:90] for r in runs if not r["reached"]}),
        }
        rows.append(row)
        print(
            f"  {name}: {reached}/{len(runs)} reached, {row['failed_mean']:.1f} failed actions "
            f"on average",
            file=sys.stderr,
            flush=True,
        )
    total_runs = sum(r["runs"] for r in rows)
    total_reached = sum(r["reached"] for r in rows)
    print(
        f"# goal-reached rate at fail rate {args.fail_rate} ({seeds} seeds per problem, "
        f"max {args.max_replans} replans, {os.cpu_count()} CPUs)\n"
    )
    print(
        "| problem | runs | reached | rate | actions run (median) | failed (mean) | retries | "
        "continues | repairs | replans | time s (median) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {r['problem']} | {r['runs']} | {r['reached']} | {r['rate']:.0%} | "
            f"{r['executed_median']:.0f} | {r['failed_mean']:.1f} | {r['retries_mean']:.1f} | "
            f"{r['continues_mean']:.1f} | {r['repairs_mean']:.1f} | {r['replans_mean']:.1f} | "
            f"{r['time_median_s']:.2f} |"
        )
    print(
        f"\n**overall: {total_reached}/{total_runs} runs reached the goal "
        f"({total_reached / total_runs:.1%})**; "
        f"median per-problem rate {statistics.median(r['rate'] for r in rows):.0%}; "
        f"elapsed {time.perf_counter() - started:.0f} s"
    )
    missed = [(r["problem"], why) for r in rows for why in r["why_missed"]]
    if missed:
        print("\nwhy runs missed the goal:\n")
        for name, why in missed:
            print(f"* {name}: {why}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(
                {"fail_rate": args.fail_rate, "seeds": seeds, "rows": rows},
                fh,
                indent=2,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
