"""Is a seeded simulated run a function of its seed? The same runs, repeated under load.

Usage::

    .venv/bin/python benchmarks/seed_repeatability.py                  # 12 configurations x 5
    .venv/bin/python benchmarks/seed_repeatability.py --repeats 3 --busy 2 --json out.json
    .venv/bin/python benchmarks/seed_repeatability.py --dispatch-cost 11   # what turns cost

Configurations: ``domains/timed_courier`` (a temporal plan: steps run in the temporal
dispatcher's threads) problems p01 and p02, and ``domains/two_robot_delivery
--concurrent`` (the plan's layers run as smach.Concurrence, one thread per robot),
seeds 1-4, fail rate 0.3, time scale 0 (as fast as it goes). Each configuration is run
``--repeats`` times, each run a fresh ``python -m plan_bridge run ... --json`` process
(its own hash seed, a cold planner worker), while ``--busy`` processes spin beside
them (a core taken: threads are scheduled differently from one run to the next). A
configuration *repeats* when every run gave the same executed steps, decisions, outcome
and fault counts (faults injected, actions failed). The script prints one row per
configuration and exits 1 when one of them did not repeat.

The script runs the source tree it lies in (``src/`` next to it), so a copy of it in an
older checkout measures that checkout.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

#: What must be identical in every run of a configuration (keys of ``run --json``).
COMPARED = {
    "steps": ("executed",),
    "decisions": ("decisions",),
    "outcome": ("outcome", "goal_reached"),
    "faults": ("faults_injected", "actions_failed"),
}


@dataclass(frozen=True)
class Config:
    domain: str
    problem: str | None
    seed: int
    concurrent: bool = False

    @property
    def name(self) -> str:
        problem = f" {self.problem}" if self.problem else ""
        flag = " --concurrent" if self.concurrent else ""
        return f"{self.domain}{problem}{flag} seed {self.seed}"

    def argv(self, fail_rate: float, time_scale: float) -> list[str]:
        argv = ["run", str(ROOT / "domains" / self.domain)]
        if self.problem:
            argv += ["--problem", self.problem]
        if self.concurrent:
            argv.append("--concurrent")
        argv += ["--seed", str(self.seed), "--fail-rate", f"{fail_rate:g}"]
        argv += ["--time-scale", f"{time_scale:g}", "--json", "--quiet"]
        return argv


def configurations(seeds: list[int], problems: list[str]) -> list[Config]:
    configs = [Config("timed_courier", p, s) for p in problems for s in seeds]
    configs += [Config("two_robot_delivery", None, s, concurrent=True) for s in seeds]
    return configs


def run_once(config: Config, fail_rate: float, time_scale: float) -> dict[str, Any]:
    """One run in a fresh process; the compared figures (or the error it gave)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    env.pop("PYTHONHASHSEED", None)  # every run its own hash seed, as a user's runs
    proc = subprocess.run(
        [sys.executable, "-m", "plan_bridge", *config.argv(fail_rate, time_scale)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    try:
        data: dict[str, Any] = json.loads(proc.stdout)
    except json.JSONDecodeError:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:]
        return {"error": f"exit {proc.returncode}: {' '.join(tail)}"}
    figures = {key: data.get(key) for keys in COMPARED.values() for key in keys}
    figures["sim_time_s"] = data.get("sim_time_s")
    return figures


def compare(runs: list[dict[str, Any]]) -> dict[str, bool]:
    """Per compared group, whether every run agrees with the first."""
    if any("error" in run for run in runs):
        return dict.fromkeys(COMPARED, False)
    return {
        group: all(all(run[k] == runs[0][k] for k in keys) for run in runs)
        for group, keys in COMPARED.items()
    }


def spin_up(count: int) -> list[subprocess.Popen[bytes]]:
    """``count`` processes that keep a core busy until killed."""
    return [
        subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)
    ]  # fmt: skip


def summary(run: dict[str, Any]) -> str:
    if "error" in run:
        return str(run["error"])
    steps = len(run["executed"] or [])
    return (
        f"{run['outcome']}, {steps} steps, {len(run['decisions'] or [])} decisions, "
        f"{run['faults_injected']} faults, sim {run['sim_time_s']} s"
    )


def dispatch_cost(runs: int) -> dict[str, float]:
    """Median wall milliseconds of dispatching timed_courier p01's plan (no faults,
    TimedWorld skills, no listeners) on the world's simulated clock and on the wall
    clock, ``runs`` each, alternating: what taking turns costs."""
    import statistics

    from plan_bridge.belief import Belief
    from plan_bridge.execution.clock import WALL_CLOCK
    from plan_bridge.execution.semantics import ActionModel
    from plan_bridge.execution.temporal import compile_temporal
    from plan_bridge.execution.timed_world import TimedWorld, timed_skills
    from plan_bridge.pddl.task import load_task
    from plan_bridge.planning.planner import get_planner

    courier = ROOT / "domains" / "timed_courier"
    task = load_task(courier / "domain.pddl", courier / "problems" / "p01.pddl")
    plan = get_planner("auto").solve(task, timeout=60).actions
    times: dict[str, list[float]] = {"simulated clock": [], "wall clock": []}
    for n in range(runs):
        for name, samples in times.items():
            world = TimedWorld(task, seed=n)
            model = ActionModel(task)
            belief = Belief(task.initial_facts, model.initial_values())
            clock = None if name == "simulated clock" else WALL_CLOCK  # None: the world's
            compiled = compile_temporal(
                plan, timed_skills(world), model, belief, world=world, clock=clock
            )
            began = time.perf_counter()
            outcome = compiled.machine.execute()
            samples.append(time.perf_counter() - began)
            if outcome != "succeeded":
                raise SystemExit(f"the dispatch on the {name} ended {outcome}")
    return {name: statistics.median(samples) * 1000 for name, samples in times.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per configuration")
    parser.add_argument("--seeds", default="1,2,3,4", help="comma-separated (default 1-4)")
    parser.add_argument("--problems", default="p01,p02", help="timed_courier problems")
    parser.add_argument("--fail-rate", type=float, default=0.3)
    parser.add_argument("--time-scale", type=float, default=0.0)
    parser.add_argument("--busy", type=int, default=1, help="busy processes beside the runs")
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument(
        "--dispatch-cost",
        type=int,
        metavar="RUNS",
        help="instead: time timed_courier p01's dispatch on the simulated and the wall clock",
    )
    args = parser.parse_args(argv)
    if args.dispatch_cost:
        medians = dispatch_cost(args.dispatch_cost)
        print(
            f"timed_courier p01 dispatch, median of {args.dispatch_cost}: "
            + ", ".join(f"{name} {ms:.1f} ms" for name, ms in medians.items())
        )
        return 0
    if args.repeats < 2:
        parser.error("--repeats must be at least 2 (a run is compared with its repeats)")
    seeds = [int(s) for s in args.seeds.split(",") if s]
    configs = configurations(seeds, [p for p in args.problems.split(",") if p])
    print(
        f"{len(configs)} configurations x {args.repeats} runs, fail rate {args.fail_rate:g}, "
        f"time scale {args.time_scale:g}, {args.busy} busy process(es) beside, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}",
        flush=True,
    )
    header = (
        f"{'configuration':<42} {'steps':>5} {'decisions':>9} {'outcome':>7} {'faults':>6}  run"
    )
    print(header)
    rows: list[dict[str, Any]] = []
    busy = spin_up(args.busy)
    began = time.monotonic()
    try:
        for config in configs:
            runs = [run_once(config, args.fail_rate, args.time_scale) for _ in range(args.repeats)]
            same = compare(runs)
            marks = [("yes" if same[g] else "NO") for g in COMPARED]
            distinct = len({json.dumps(r, sort_keys=True) for r in runs})
            what = summary(runs[0]) if all(same.values()) else f"{distinct} different runs"
            print(
                f"{config.name:<42} {marks[0]:>5} {marks[1]:>9} {marks[2]:>7} {marks[3]:>6}  {what}",
                flush=True,
            )
            rows.append({"configuration": config.name, "same": same, "runs": runs})
    finally:
        for process in busy:
            process.kill()
            process.wait()
    repeated = sum(all(row["same"].values()) for row in rows)
    print(
        f"\n{repeated}/{len(rows)} configurations repeated exactly over {args.repeats} runs "
        f"({time.monotonic() - began:.0f} s)"
    )
    if args.json:
        result = {
            "repeats": args.repeats,
            "fail_rate": args.fail_rate,
            "time_scale": args.time_scale,
            "busy": args.busy,
            "rows": rows,
            "repeated": repeated,
        }
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0 if repeated == len(rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
