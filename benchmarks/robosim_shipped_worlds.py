"""pyrobosim's own worlds as targets: how often each goal is reached, in how much
simulated and wall time.

Usage::

    .venv/bin/python benchmarks/robosim_shipped_worlds.py               # 10 seeds, fail rate 0.2
    .venv/bin/python benchmarks/robosim_shipped_worlds.py --seeds 3 --fail-rate 0
    .venv/bin/python benchmarks/robosim_shipped_worlds.py --world test_world_multirobot

Each run is ``plan-bridge run WORLD.yaml --goal GOAL --seed N --fail-rate R`` done in
process, WORLD one of the world files pyrobosim ships (``pyrobosim.utils.general.
get_data_folder()``: test_world, test_world_multirobot, pddlstream_simple_world,
roscon_2024_workshop_world). The planner workers are warm after a first run, which is
not counted. "sim s" is the world's simulated time at the end of a run, "wall s" that
of ``Mission.run()`` (planning included); both are means over the seeds.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

#: (world, goal): goals in pyrobosim's vocabulary with each world's own names.
GOALS: tuple[tuple[str, str], ...] = (
    ("test_world", "(At apple0 table0_tabletop)"),
    ("test_world", "(At water0 my_desk)"),
    ("test_world", "(and (IsOpen trash) (At fuji counter0_left))"),
    ("test_world_multirobot", "(and (At robot0 bathroom) (At robot2 kitchen))"),
    ("test_world_multirobot", "(and (Holding robot0 gala) (Holding robot1 water0))"),
    ("test_world_multirobot", "(and (At banana0 my_desk_desktop) (At apple0 counter0_left))"),
    ("pddlstream_simple_world", "(At apple0 table0_tabletop)"),
    ("pddlstream_simple_world", "(and (At apple1 desk0) (At water0 table0))"),
    ("roscon_2024_workshop_world", "(At soda0 table_tabletop)"),
    ("roscon_2024_workshop_world", "(and (At waste0 dumpster) (At robot charger_dock))"),
)


def world_file(name: str) -> Path:
    from pyrobosim.utils.general import get_data_folder

    return Path(get_data_folder()) / f"{name}.yaml"


def one_run(world: str, goal: str, seed: int, fail_rate: float) -> dict[str, float]:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.runner import MissionOptions, prepare_mission
    from plan_bridge.robosim.world import RobosimWorld

    mission = prepare_mission(
        load_target(world_file(world), goal=goal), MissionOptions(seed=seed, fail_rate=fail_rate)
    )
    robosim = mission.world
    assert isinstance(robosim, RobosimWorld)
    began = time.perf_counter()
    mission.run()
    wall = time.perf_counter() - began
    robosim.close()
    report = mission.executive.report
    return {
        "goal": float(report.goal_reached and robosim.goal_reached()),
        "sim": robosim.now(),
        "wall": wall,
        "faults": float(robosim.faults),
        "replans": float(report.replans),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--world", default="", help="only the goals of this world")
    args = parser.parse_args()
    goals = [(w, g) for w, g in GOALS if not args.world or w == args.world]
    if not goals:
        parser.error(f"no goals of a world named {args.world!r}")
    one_run(*goals[0], 0, args.fail_rate)  # warm-up: worker processes, imports
    print(f"pyrobosim's shipped worlds, seeds 1..{args.seeds}, fail rate {args.fail_rate:g}")
    print(
        "| world | goal | fail rate | seeds | reached | faults | replans | sim s | wall s |\n"
        "|---|---|---|---|---|---|---|---|---|"
    )
    total_sim = total_wall = 0.0
    reached = runs = 0
    for world, goal in goals:
        results = [one_run(world, goal, s, args.fail_rate) for s in range(1, args.seeds + 1)]
        hits = int(sum(r["goal"] for r in results))
        reached += hits
        runs += len(results)
        total_sim += sum(r["sim"] for r in results)
        total_wall += sum(r["wall"] for r in results)
        print(
            f"| {world} | `{goal}` | {args.fail_rate:g} | {len(results)} | {hits}/{len(results)} "
            f"| {statistics.mean(r['faults'] for r in results):.1f} "
            f"| {statistics.mean(r['replans'] for r in results):.1f} "
            f"| {statistics.mean(r['sim'] for r in results):.1f} "
            f"| {statistics.mean(r['wall'] for r in results):.2f} |",
            flush=True,
        )
    print(
        f"total: {reached}/{runs} goals reached, {total_sim / total_wall:.1f} simulated s per "
        f"wall s"
    )


if __name__ == "__main__":
    main()
