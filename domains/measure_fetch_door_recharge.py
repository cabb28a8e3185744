"""Measure planned vs scripted success rates and times of three PR2 missions.

    .venv/bin/python domains/measure_fetch_door_recharge.py            # 20 seeds each
    .venv/bin/python domains/measure_fetch_door_recharge.py --seeds 5 --missions recharge

For fetch_drink (p01), door_opening (p02) and recharge (p02), at fault rates 0, 0.1
and 0.2, it runs every seed planned (the executive with the domain's skills, a fresh
Fast Downward planner call for every plan: no memoising, so the times are real) and
scripted (the domain's hand-written baseline), and prints one Markdown table row per
mission, mode and rate: goals reached, wall time per run (planning included), simulated
robot time per run, planner calls and faults per run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import Target, load_target
from plan_bridge.planning.planner import Planner, get_planner

HERE = Path(__file__).resolve().parent
MISSIONS = {"fetch_drink": "p01", "door_opening": "p02", "recharge": "p02"}
RATES = (0.0, 0.1, 0.2)


@dataclass(frozen=True)
class Row:
    mission: str
    problem: str
    mode: str
    fail_rate: float
    reached: int
    runs: int
    wall_s: float
    sim_s: float
    planner_calls: float
    faults: float

    def markdown(self) -> str:
        calls = f"{self.planner_calls:.1f}" if self.mode == "planned" else "-"
        return (
            f"| {self.mission} | {self.problem} | {self.mode} | {self.fail_rate:g} | "
            f"{self.reached}/{self.runs} ({self.reached / self.runs:.0%}) | {self.wall_s:.2f} | "
            f"{self.sim_s:.0f} | {calls} | {self.faults:.1f} |"
        )


def measure(target: Target, mode: str, fail_rate: float, seeds: range, planner: Planner) -> Row:
    reached, walls, sims, calls, faults = 0, [], [], [], []
    assert target.module is not None
    for seed in seeds:
        started = time.monotonic()
        if mode == "planned":
            setup = target.setup(seed=seed, fail_rate=fail_rate)
            executive = Executive(target.task, setup.skills, planner, sense=setup.sense)
            executive.execute()
            world = setup.world
            calls.append(executive.report.planner_calls)
        else:
            baseline = target.module.scripted(target.task, seed=seed, fail_rate=fail_rate)
            baseline.machine.execute()
            world = baseline.world
        walls.append(time.monotonic() - started)
        reached += world.goal_reached()
        sims.append(world.sim_time)
        faults.append(world.faults_injected)
    return Row(
        target.name,
        target.problem_path.stem,
        mode,
        fail_rate,
        reached,
        len(seeds),
        statistics.fmean(walls),
        statistics.fmean(sims),
        statistics.fmean(calls) if calls else 0.0,
        statistics.fmean(faults),
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--missions", nargs="*", default=list(MISSIONS), choices=list(MISSIONS))
    args = parser.parse_args(argv)
    planner = get_planner("fast-downward")
    print(
        "| mission | problem | mode | fail rate | goals reached | wall s/run | simulated s/run | planner calls/run | faults/run |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.missions:
        target = load_target(HERE / name, MISSIONS[name])
        for mode in ("planned", "scripted"):
            for rate in RATES:
                row = measure(target, mode, rate, range(args.seeds), planner)
                print(row.markdown(), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
