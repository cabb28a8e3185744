"""The PR2 missions on pyrobosim: how often each reaches its goal with faults and a
hallway closed on the robot's way at a seeded moment, planned and scripted.

Usage::

    .venv/bin/python benchmarks/robosim_missions.py                 # 20 seeds, fail rate 0.2
    .venv/bin/python benchmarks/robosim_missions.py --seeds 5 --missions house_doors,fetch

Each run is ``plan-bridge run TARGET --problem GOAL --seed N --fail-rate R --events
TARGET/events/VARIANT.yaml`` (planned) or the world folder's scripted baseline on the
same world, goal, seed and events, done in this process (the first run of each mission
warms the planner workers and is not timed, but its outcome counts). The events files
draw the hallway's closing time from the seed (``at: [LO, HI]``), so every seed closes
it at another moment. Prints one row per mission and approach: goal reached (of N),
mean simulated time, distance and wall time, and the runs that failed with why.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
DOMAINS = ROOT / "domains"


@dataclass(frozen=True)
class Mission:
    name: str
    folder: str
    goal: str
    variant: str
    story: str


MISSIONS = (
    Mission(
        "fetch", "robosim_fetch", "fetch_soda", "close_hallway_seeded",
        "fetch a soda from a closed fridge; charge first (25 % battery)",
    ),
    Mission(
        "house_doors", "robosim_house", "through_doors", "lock_study_door",
        "reach the study through closed doors",
    ),
    Mission(
        "house_table", "robosim_house", "clear_table", "close_dining_kitchen",
        "clear the dining table onto the kitchen counter",
    ),
    Mission(
        "house_inspect", "robosim_house", "inspect_all", "close_dining_kitchen",
        "look at every table, counter and desk",
    ),
    Mission(
        "two_robots", "robosim_two_robots", "", "close_hallway",
        "two robots deliver at once",
    ),
)  # fmt: skip


def _planned(mission: Mission, seed: int, fail_rate: float) -> dict[str, Any]:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.runner import MissionOptions, prepare_mission
    from plan_bridge.robosim.world import RobosimWorld

    folder = DOMAINS / mission.folder
    target = load_target(
        folder, mission.goal or None, events=folder / "events" / f"{mission.variant}.yaml"
    )
    prepared = prepare_mission(target, MissionOptions(seed=seed, fail_rate=fail_rate))
    world = prepared.world
    assert isinstance(world, RobosimWorld)
    began = time.perf_counter()
    prepared.run()
    wall = time.perf_counter() - began
    report = prepared.executive.report
    world.close()
    return {
        "reached": bool(report.goal_reached),
        "sim": world.now(),
        "distance": world.distance_m,
        "wall": wall,
        "why": "" if report.goal_reached else report.explanation,
    }


def _scripted(mission: Mission, seed: int, fail_rate: float) -> dict[str, Any]:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.robosim.world import RobosimWorld

    target = load_target(DOMAINS / mission.folder, mission.goal or None)
    assert target.module is not None
    built = target.module.scripted(
        target.task, seed=seed, fail_rate=fail_rate, variant=mission.variant
    )
    world = built.world
    assert isinstance(world, RobosimWorld)
    began = time.perf_counter()
    outcome = built.machine.execute()
    wall = time.perf_counter() - began
    world.close()
    reached = world.goal_reached()
    return {
        "reached": reached,
        "sim": world.now(),
        "distance": world.distance_m,
        "wall": wall,
        "why": "" if reached else f"the machine ended {outcome}",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument(
        "--missions", default=",".join(m.name for m in MISSIONS), help="comma-separated"
    )
    parser.add_argument("--approaches", default="planned,scripted")
    args = parser.parse_args()
    from plan_bridge.robosim.loading import import_pyrobosim

    import_pyrobosim()
    wanted = args.missions.split(",")
    unknown = sorted(set(wanted) - {m.name for m in MISSIONS})
    if unknown:
        parser.error(f"unknown missions {unknown}; missions: {[m.name for m in MISSIONS]}")
    runners = {"planned": _planned, "scripted": _scripted}
    print(
        f"{args.seeds} seeds (1..{args.seeds}) per mission, fail rate {args.fail_rate}, "
        "a hallway closed at a seeded moment"
    )
    header = (
        f"{'mission':<14} {'approach':<9} {'reached':>8} {'sim s':>7} {'metres':>7} {'wall s':>7}"
    )
    print(header)
    print("-" * len(header))
    failures: list[str] = []
    for mission in (m for m in MISSIONS if m.name in wanted):
        if not (DOMAINS / mission.folder).is_dir():
            print(f"{mission.name:<14} (no {mission.folder} folder)")
            continue
        for approach in args.approaches.split(","):
            rows = []
            for seed in range(1, args.seeds + 1):
                row = runners[approach](mission, seed, args.fail_rate)
                rows.append(row)
                if not row["reached"]:
                    failures.append(f"{mission.name} {approach} seed {seed}: {row['why']}")
            timed = rows[1:] or rows
            reached = sum(r["reached"] for r in rows)
            print(
                f"{mission.name:<14} {approach:<9} {reached:>4}/{len(rows):<3} "
                f"{statistics.fmean(r['sim'] for r in rows):>7.1f} "
                f"{statistics.fmean(r['distance'] for r in rows):>7.1f} "
                f"{statistics.fmean(r['wall'] for r in timed):>7.2f}",
                flush=True,
            )
    for line in failures:
        print("not reached:", line.splitlines()[0][:200])


if __name__ == "__main__":
    main()
