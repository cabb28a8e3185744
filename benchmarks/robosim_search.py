"""Looking for things (issue 36): an object moved or taken away while the robot drives
to it, planned search against a scripted one over the same skills.

Usage::

    .venv/bin/python benchmarks/robosim_search.py                    # 20 seeds, fail rate 0.2
    .venv/bin/python benchmarks/robosim_search.py --seeds 3 --jobs 1 # a smoke run

Cases (each run is ``plan-bridge run TARGET --goal GOAL --events EVENTS --seed N
--fail-rate R`` done in a worker process; the scripted runs use
``domains/robosim_search/scripted.py``'s machine on the same world and events):

* ``search moved``: ``domains/robosim_search``, ``find_and_fetch``, ``events/moved.yaml``
  (the soda moved at a seeded moment to a seeded place of the house);
* ``test_world moved``: pyrobosim's ``test_world``, ``(Holding robot soda)``,
  ``benchmarks/data/test_world_soda_moved.yaml``;
* ``search moved 2 robots`` / ``search taken 2 robots``: the same on
  ``world_two_robots.yaml`` (a second robot in the foyer), planned only: the robots
  split the places to look at (``taken`` is compared with the one-robot sweep);
* ``... taken``: the soda removed instead (``events/taken.yaml``,
  ``test_world_soda_taken.yaml``): the run must end with exit 1 (aborted), a reason
  naming the soda and the places searched, in at most the time of one **sweep** (the
  scripted search's nearest-first tour of every place, with the object gone, at the
  same seed and fault rate; within :data:`SWEEP_SLACK`: the simulated paths differ by
  centimetres).

Per case and approach: goal rate, mean simulated time, time to find (simulated seconds
until the robot saw the object again, runs that found it), distance driven, places
searched (where the object was looked for and not found).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT))

SEARCH = ROOT / "domains" / "robosim_search"
#: A planned search that finds nothing may take this share longer than the sweep.
SWEEP_SLACK = 0.02
DATA = ROOT / "benchmarks" / "data"
#: ``find_and_fetch`` of goals.yaml (a world file names no goals file).
FIND_AND_FETCH = "(and (At soda foyer_table_tabletop) (HandEmpty robot))"


@dataclass(frozen=True)
class Case:
    name: str
    world: str
    """A world folder, or the name of a pyrobosim world file."""
    goal: str
    events: Path
    item: str = "soda"
    taken: bool = False
    robots: int = 1
    sweep: str = ""
    """The case whose scripted runs are the sweep of a taken case (default: itself)."""


CASES = (
    Case("search moved", str(SEARCH), "find_and_fetch", SEARCH / "events" / "moved.yaml"),
    Case(
        "test_world moved",
        "test_world",
        "(Holding robot soda)",
        DATA / "test_world_soda_moved.yaml",
    ),
    Case(
        "search taken",
        str(SEARCH),
        "find_and_fetch",
        SEARCH / "events" / "taken.yaml",
        taken=True,
    ),
    Case(
        "search moved 2 robots",
        str(SEARCH / "world_two_robots.yaml"),
        FIND_AND_FETCH,
        SEARCH / "events" / "moved.yaml",
        robots=2,
    ),
    Case(
        "search taken 2 robots",
        str(SEARCH / "world_two_robots.yaml"),
        FIND_AND_FETCH,
        SEARCH / "events" / "taken.yaml",
        taken=True,
        robots=2,
        sweep="search taken",
    ),
    Case(
        "test_world taken",
        "test_world",
        "(Holding robot soda)",
        DATA / "test_world_soda_taken.yaml",
        taken=True,
    ),
)


def target_path(world: str) -> Path:
    if Path(world).exists():
        return Path(world)
    from pyrobosim.utils.general import get_data_folder

    return Path(get_data_folder()) / f"{world}.yaml"


def planned(case: Case, seed: int, fail_rate: float) -> dict[str, Any]:
    """One planned run: outcome, reason, figures, time to find."""
    from plan_bridge.belief.whereabouts import ABSENT, places_of
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.runner import MissionOptions, prepare_mission
    from plan_bridge.robosim.world import RobosimWorld

    target = load_target(target_path(case.world), goal=case.goal, events=case.events)
    mission = prepare_mission(target, MissionOptions(seed=seed, fail_rate=fail_rate))
    world = mission.world
    assert isinstance(world, RobosimWorld)
    belief = mission.executive.belief
    found: dict[str, float] = {}
    lost = [False]
    searched: set[str] = set()

    def watch() -> None:
        facts = belief.facts
        absent = {f[2] for f in facts if f[0] == ABSENT and f[1] == case.item}
        searched.update(absent)
        if absent:
            lost[0] = True
        at, held = places_of(facts)
        if lost[0] and (case.item in at or case.item in held) and "t" not in found:
            found["t"] = world.now()

    belief.add_listener(watch)
    try:
        outcome = mission.run()
        report = mission.executive.report
        figures = world.figures()
        return {
            "outcome": outcome,
            "goal": world.goal_reached(),
            "reason": report.explanation,
            "sim": figures["sim_time_s"],
            "metres": figures["distance_m"],
            "found": found.get("t"),
            "searched": len(searched),
        }
    finally:
        world.close()


def scripted(case: Case, seed: int, fail_rate: float) -> dict[str, Any]:
    """One run of the scripted search and fetch on the same world and events."""
    from domains.robosim_search.scripted import find_and_fetch

    from plan_bridge.maps.goals import parse_goal
    from plan_bridge.robosim.events import load_events
    from plan_bridge.robosim.world import RobosimWorld

    path = target_path(case.world)
    file = path / "world.yaml" if path.is_dir() else path
    goal_text = case.goal
    if path.is_dir():
        from plan_bridge.robosim.target_files import read_goals

        goal_text = read_goals(path).get(case.goal, case.goal)
    world = RobosimWorld(file, seed=seed, fail_rate=fail_rate, events=load_events(case.events))
    try:
        world.goal = tuple(parse_goal(goal_text, world.model))
        machine = find_and_fetch(world, world.goal)
        outcome = machine.execute()
        figures = world.figures()
        return {
            "outcome": outcome,
            "goal": world.goal_reached(),
            "reason": f"searched {len(machine.userdata.searched)} places",
            "sim": figures["sim_time_s"],
            "metres": figures["distance_m"],
            "found": machine.userdata.found_at,
            "searched": len(machine.userdata.searched) - (machine.userdata.found_at is not None),
        }
    finally:
        world.close()


def approaches(case: Case) -> tuple[str, ...]:
    """The scripted search is for one robot."""
    return ("planned",) if case.robots > 1 else ("planned", "scripted")


def one(job: tuple[str, Case, int, float]) -> tuple[str, Case, int, dict[str, Any]]:
    approach, case, seed, fail_rate = job
    run = planned if approach == "planned" else scripted
    return approach, case, seed, run(case, seed, fail_rate)


def mean(values: list[float]) -> str:
    return f"{statistics.fmean(values):.1f}" if values else "n/a"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds 1..N (default 20)")
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--cases", default="", help="comma-separated case names (default all)")
    args = parser.parse_args(argv)
    chosen = [c for c in CASES if not args.cases or c.name in args.cases.split(",")]
    jobs = [
        (approach, case, seed, args.fail_rate)
        for case in chosen
        for approach in approaches(case)
        for seed in range(1, args.seeds + 1)
    ]
    results: dict[tuple[str, str], list[dict[str, Any]]] = {}
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for approach, case, _seed, result in pool.map(one, jobs):
            results.setdefault((case.name, approach), []).append(result)
    print(f"fail rate {args.fail_rate}, seeds 1-{args.seeds}")
    print()
    print(
        "| case | approach | goal reached | mean sim s | mean time to find s | "
        "mean distance m | mean places searched | ended as required |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for case in chosen:
        for approach in approaches(case):
            runs = results.get((case.name, approach), [])
            reached = sum(1 for r in runs if r["goal"])
            finds = [float(r["found"]) for r in runs if r["found"] is not None]
            if case.taken:
                sweeps = results.get((case.sweep or case.name, "scripted"), [])
                ratios = [
                    float(r["sim"]) / max(1e-9, float(w["sim"]))
                    for r, w in zip(runs, sweeps, strict=True)
                ]
                good = sum(
                    1
                    for r, ratio in zip(runs, ratios, strict=True)
                    if r["outcome"] == "aborted"
                    and (approach == "scripted" or case.item in r["reason"])
                    and ratio <= 1 + SWEEP_SLACK
                )
                most = max(ratios, default=0.0)
                ended = f"{good}/{len(runs)} exit 1 within a sweep (at most {most:.3f} sweeps)"
            else:
                ended = "-"
            print(
                f"| {case.name} | {approach} | {reached}/{len(runs)} | "
                f"{mean([float(r['sim']) for r in runs])} | {mean(finds)} | "
                f"{mean([float(r['metres']) for r in runs])} | "
                f"{mean([float(r['searched']) for r in runs])} | {ended} |"
            )
    for case in chosen:
        for r in results.get((case.name, "planned"), []):
            if case.taken or not r["goal"]:
                print(f"{case.name} planned: {r['outcome']}: {r['reason']}")
                break
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
