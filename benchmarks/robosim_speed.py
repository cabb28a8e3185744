"""How fast a pyrobosim mission runs: simulated seconds per wall second, and where the
wall time goes (planner, pyrobosim, the executive).

Usage::

    .venv/bin/python benchmarks/robosim_speed.py                # 5 seeds, fail rate 0.2, events
    .venv/bin/python benchmarks/robosim_speed.py --seeds 10 --fail-rate 0 --no-events

Each run is ``plan-bridge run domains/robosim_fetch --seed N --fail-rate R --events
domains/robosim_fetch/events/close_hallway.yaml`` done in process (the world and the
planner workers are warm after the first run, which is not counted). Wall time is that
of ``Mission.run()``; "pyrobosim" is the time spent in pyrobosim's path planning and
actions (its path executor sleeps 0.1 s after every drive); "executive" is the rest of
the execution time (the executive, SMACH, belief updates, sensing).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
FETCH = ROOT / "domains" / "robosim_fetch"


def one_run(seed: int, fail_rate: float, events: Path | None) -> dict[str, float]:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.runner import MissionOptions, prepare_mission
    from plan_bridge.robosim.world import RobosimWorld

    mission = prepare_mission(
        load_target(FETCH, events=events), MissionOptions(seed=seed, fail_rate=fail_rate)
    )
    world = mission.world
    assert isinstance(world, RobosimWorld)
    began = time.perf_counter()
    mission.run()
    wall = time.perf_counter() - began
    report = mission.executive.report
    execution = wall - report.planning_time_s
    world.close()
    return {
        "goal": float(report.goal_reached),
        "sim": world.now(),
        "wall": wall,
        "planning": report.planning_time_s,
        "pyrobosim": world.robot_wall_s,
        "executive": max(0.0, execution - world.robot_wall_s),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--no-events", action="store_true")
    args = parser.parse_args()
    events = None if args.no_events else FETCH / "events" / "close_hallway.yaml"
    one_run(0, args.fail_rate, events)  # warm-up: worker processes, imports
    runs = [one_run(seed, args.fail_rate, events) for seed in range(1, args.seeds + 1)]
    print(
        f"robosim_fetch, {args.seeds} seeds, fail rate {args.fail_rate:g}, events: {events is not None}"
    )
    print("seed  goal  sim s  wall s  sim/wall  planning  pyrobosim  executive")
    for seed, run in enumerate(runs, start=1):
        print(
            f"{seed:>4}  {'yes' if run['goal'] else 'no':>4}  {run['sim']:5.1f}  {run['wall']:6.2f}  "
            f"{run['sim'] / run['wall']:8.1f}  {run['planning']:8.2f}  {run['pyrobosim']:9.2f}  "
            f"{run['executive']:9.2f}"
        )
    sim = sum(r["sim"] for r in runs)
    wall = sum(r["wall"] for r in runs)
    execution_wall = sum(r["wall"] - r["planning"] for r in runs)
    print(
        f"total: {sum(r['goal'] for r in runs):.0f}/{len(runs)} goals, {sim / wall:.1f} simulated s "
        f"per wall s ({sim / execution_wall:.1f} without planning); executive "
        f"{100 * sum(r['executive'] for r in runs) / wall:.1f}% of wall time, pyrobosim "
        f"{100 * sum(r['pyrobosim'] for r in runs) / wall:.1f}%, planning "
        f"{100 * sum(r['planning'] for r in runs) / wall:.1f}% "
        f"(median wall {statistics.median(r['wall'] for r in runs):.2f} s)"
    )


if __name__ == "__main__":
    main()
