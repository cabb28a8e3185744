"""How often a seeded temporal mission with faults repeats itself, run after run.

Usage::

    .venv/bin/python benchmarks/temporal_repeatability.py               # 12 seeds x 2 problems x 3
    .venv/bin/python benchmarks/temporal_repeatability.py --seeds 2 --repeats 2 --json out.json

Each (problem, seed) of ``domains/timed_courier`` is run ``--repeats`` times with
``plan-bridge run --fail-rate F --json`` in this process (a warm planner worker, as a
study worker has), at ``--time-scale`` 0 (as fast as it goes, the default of
``plan-bridge run``). A configuration *repeats* when every run gave the same outcome,
faults, replans, retries, repairs and executed steps. Faults are drawn per step
(seed, step, attempt); what used to differ was the order of two near-simultaneous
events in the dispatcher's threads (which steps had started when one failed). Since
the dispatch takes turns on the world's simulated clock, every configuration should
repeat; ``benchmarks/seed_repeatability.py`` checks it in fresh processes under load.
The script reports the share of configurations that repeat and the share whose
goal-reached verdict differs between runs.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

COURIER = ROOT / "domains" / "timed_courier"
COMPARED = ("outcome", "goal_reached", "faults_injected", "replans", "retries", "repairs")


def run_once(problem: str, seed: int, fail_rate: float) -> dict[str, Any]:
    from plan_bridge.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(
            ["run", str(COURIER), "--problem", problem, "--seed", str(seed),
             "--fail-rate", str(fail_rate), "--time-scale", "0", "--json", "--quiet"]
        )  # fmt: skip
    data: dict[str, Any] = json.loads(out.getvalue())
    summary = {key: data[key] for key in COMPARED}
    summary["executed"] = len(data["executed"])
    summary["exit"] = code
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=12)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--fail-rate", type=float, default=0.3)
    parser.add_argument("--problems", default="p01,p02")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    if args.repeats < 2:
        parser.error("--repeats must be at least 2 (a run is compared with its repeats)")
    rows = []
    for problem in args.problems.split(","):
        for seed in range(args.seeds):
            runs = [run_once(problem, seed, args.fail_rate) for _ in range(args.repeats)]
            same = all(r == runs[0] for r in runs)
            verdicts = {r["goal_reached"] for r in runs}
            rows.append(
                {"problem": problem, "seed": seed, "repeats": same, "runs": runs,
                 "goal_verdict_differs": len(verdicts) > 1}
            )  # fmt: skip
            counts = " | ".join(
                f"{r['outcome']} faults {r['faults_injected']} replans {r['replans']} "
                f"retries {r['retries']} steps {r['executed']}"
                for r in runs
            )
            print(f"{problem} seed {seed:2d}: {'same' if same else 'DIFFERS'}: {counts}")
    repeated = sum(r["repeats"] for r in rows)
    flipped = sum(r["goal_verdict_differs"] for r in rows)
    print(
        f"\n{repeated}/{len(rows)} configurations repeated exactly over {args.repeats} runs; "
        f"{flipped}/{len(rows)} had runs that disagree on reaching the goal "
        f"(fail rate {args.fail_rate:g}, time scale 0)"
    )
    if args.json:
        result = {
            "fail_rate": args.fail_rate,
            "repeats": args.repeats,
            "rows": rows,
            "repeated": repeated,
            "goal_verdict_differs": flipped,
        }
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
