"""Section (f) of plan_bridge_bench: missions with faults, per recovery policy.

Usage (also run by ``plan_bridge_bench.py --sections f``)::

    .venv/bin/python benchmarks/plan_bridge_recovery.py                # 10 seeds
    .venv/bin/python benchmarks/plan_bridge_recovery.py --seeds 3 --json f.json

Each mission is ``plan-bridge run DOMAIN --problem P --fail-rate 0.2 --seed N`` in
process: symbolic skills whose actions fail (no effect) with probability 0.2, an
Executive with a warm worker pool. Per policy and mission it reports the planner calls,
replans, repairs (retries, continues, repair prefixes), held plans, reused plans,
planning and execution time, and the planning share of the mission time. Policies:

* ``replan-only``: no repair at all: every failure goes to the planner;
* ``before``: the recovery before issue 19: one retry when the step is applicable,
  continue, goal-regression repair, replan (60 s), no held plan, no plan reuse, no
  portfolio;
* ``full``: the default policy (continue, up to three retries while the held plan is
  valid, repair, replan through the portfolio within 20 s, hold), a fresh plan cache
  per mission;
* ``full, shared cache``: the same with one plan cache for all missions of the
  problem (a study's seeds, a robot that runs the same job again): from the second
  mission on the initial plan is reused.

A second scenario, ``setback``, makes failures change the world: a failed action also
undoes the action before it with probability 0.5 (a block slips back), so the failed
step cannot start again and the held plan breaks. There, re-achieving the broken
precondition (re-doing the undone step without a planner, else goal-regression
repair: a planned prefix that re-establishes what was undone) competes with replanning: ``full, no repair`` is the default policy with
``repair=False``.

Symbolic actions take no time, so every mission's execution time is the executive's
own work; ``action ms for 30%`` is how long each executed action would have to take
for planning to be at most 30% of the mission time.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
BENCH = (ROOT / ".." / "shared" / "pddl-bench").resolve()

#: blocks probBLOCKS-14-0: an 84-step first plan; with faults the missions execute
#: 74-90 steps (the issue's "74-step IPC problem with faults").
PROBLEMS = (("blocks", "probBLOCKS-14-0"), ("visitall-sat11-strips", "problem12"))
POLICIES = ("replan-only", "before", "full", "full, shared cache")
SETBACK_POLICIES = ("before", "full, no repair", "full")


def policy_named(name: str) -> Any:
    from plan_bridge.execution.policy import ReplanPolicy

    if name == "replan-only":
        return ReplanPolicy.named("replan-only")
    if name == "before":
        return ReplanPolicy(
            max_step_retries=1,
            redo_window=0,
            hold_valid_plan=False,
            reuse_plans=False,
            replan_portfolio=(),
            replan_timeout=60.0,
        )
    if name == "full, no repair":
        return ReplanPolicy(repair=False)
    return ReplanPolicy()


def setback_world(task: Any, seed: int, fail_rate: float) -> Any:
    """A simulated world whose failed actions undo the previous action half of the time."""
    from plan_bridge.execution.simulation import SimulatedWorld

    class SetbackWorld(SimulatedWorld):
        def __init__(self) -> None:
            super().__init__(task, seed=seed, fail_rate=fail_rate)
            self._before_last: frozenset[Any] | None = None

        def perform(self, step: Any) -> Any:
            before = self.facts
            ok, observations = super().perform(step)
            if ok:
                self._before_last = before
            elif self._before_last is not None and self.rng.random() < 0.5:
                with self._lock:
                    now = set(self._facts)
                    self._facts = set(self._before_last)
                    changed = now ^ self._facts
                self.inject("setback", str(step), "the previous action was undone")
                self._before_last = None
                observations = [*observations, *((f, f in self._facts) for f in sorted(changed))]
            return ok, observations

    return SetbackWorld()


def mission(
    folder: str,
    problem: str,
    seed: int,
    fail_rate: float,
    policy: Any,
    planner: Any,
    cache: Any,
    setback: bool = False,
) -> dict[str, Any]:
    from plan_bridge.execution.executive import Executive
    from plan_bridge.execution.simulation import symbolic_skills
    from plan_bridge.missions.mission import load_target

    target = load_target(BENCH / folder / "domain.pddl", BENCH / folder / f"{problem}.pddl")
    if setback:
        world = setback_world(target.task, seed, fail_rate)
        skills = symbolic_skills(world)
    else:
        setup = target.setup(seed=seed, fail_rate=fail_rate)
        world, skills = setup.world, setup.skills
    executive = Executive(
        target.task, skills, planner, policy=replace(policy, max_replans=20), plan_cache=cache
    )
    started = time.perf_counter()
    executive.execute()
    wall = time.perf_counter() - started
    r = executive.report
    return {
        "reached": bool(r.goal_reached and world.goal_reached()),
        "executed": r.actions_executed,
        "failed": r.actions_failed,
        "planner_calls": r.planner_calls,
        "replans": r.replans,
        "retries": r.retries,
        "continues": r.continues,
        "repairs": r.repairs,
        "repair_attempts": r.repair_attempts,
        "holds": r.holds,
        "reused": r.plans_reused,
        "planning_s": r.planning_time_s,
        "execution_s": max(0.0, wall - r.planning_time_s),
        "total_s": wall,
        "won": dict(r.planners_won),
    }


def summarise(name: str, problem: str, runs: list[dict[str, Any]]) -> dict[str, Any]:
    def mean(key: str) -> float:
        return statistics.mean(float(r[key]) for r in runs)

    planning, execution, total = mean("planning_s"), mean("execution_s"), mean("total_s")
    executed = mean("executed")
    # Per-action time that would make planning 30% of the mission: P / (P + E + n d) = 0.3.
    needed = max(0.0, (planning / 0.3 - planning - execution) / executed) if executed else 0.0
    won: dict[str, int] = {}
    for r in runs:
        for key, count in r["won"].items():
            won[key] = won.get(key, 0) + count
    return {
        "problem": problem,
        "policy": name,
        "missions": len(runs),
        "reached": sum(r["reached"] for r in runs),
        "executed": executed,
        "failed": mean("failed"),
        "planner_calls": mean("planner_calls"),
        "replans": mean("replans"),
        "retries": mean("retries"),
        "continues": mean("continues"),
        "repairs": mean("repairs"),
        "repair_attempts": mean("repair_attempts"),
        "holds": mean("holds"),
        "reused": mean("reused"),
        "planning_s": planning,
        "execution_s": execution,
        "total_s": total,
        "planning_share": planning / total if total else 0.0,
        "median_share": statistics.median(r["planning_s"] / r["total_s"] for r in runs),
        "missions_within_30pct": sum(r["planning_s"] <= 0.3 * r["total_s"] for r in runs),
        "action_ms_for_30pct": needed * 1000,
        "planners_won": won,
    }


def recovery_section(
    planner: Any, seeds: int, fail_rate: float = 0.2, quick: bool = False
) -> dict[str, Any]:
    from plan_bridge.execution.plan_cache import PlanCache

    rows = []
    for folder, problem in PROBLEMS[:1] if quick else PROBLEMS:
        name = f"{folder}/{problem}"
        # Parse once in the worker, so no policy pays the first parse.
        mission(folder, problem, 0, 0.0, policy_named("before"), planner, PlanCache())
        for policy in POLICIES:
            shared = PlanCache()
            runs = []
            for seed in range(seeds):
                cache = shared if policy.endswith("shared cache") else PlanCache()
                print(f"  (f) {name} {policy} seed {seed}", file=sys.stderr, flush=True)
                runs.append(
                    mission(folder, problem, seed, fail_rate, policy_named(policy), planner, cache)
                )
            rows.append(summarise(policy, name, runs))
    folder, problem = PROBLEMS[0]
    for policy in SETBACK_POLICIES:
        runs = []
        for seed in range(seeds):
            print(
                f"  (f) setback {folder}/{problem} {policy} seed {seed}",
                file=sys.stderr,
                flush=True,
            )
            runs.append(
                mission(
                    folder,
                    problem,
                    seed,
                    fail_rate,
                    policy_named(policy),
                    planner,
                    PlanCache(),
                    setback=True,
                )
            )
        rows.append(summarise(policy, f"{folder}/{problem} (setback)", runs))
    return {"fail_rate": fail_rate, "seeds": seeds, "rows": rows}


def print_section(section: dict[str, Any], out: Any = print) -> None:
    out(
        f"## (f) missions with faults (fail rate {section['fail_rate']}, "
        f"{section['seeds']} seeds, means per mission)\n"
    )
    out(
        "| problem | policy | reached | actions | failed | planner calls | replans | retries "
        "| continues | repairs (tried) | holds | reused | planning s | execution s | mission s "
        "| planning share (of the means) | median share | missions <= 30% | action ms for 30% |"
    )
    out(
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )
    for r in section["rows"]:
        out(
            f"| {r['problem']} | {r['policy']} | {r['reached']}/{r['missions']} | "
            f"{r['executed']:.1f} | {r['failed']:.1f} | {r['planner_calls']:.1f} | "
            f"{r['replans']:.1f} | {r['retries']:.1f} | {r['continues']:.1f} | "
            f"{r['repairs']:.1f} ({r['repair_attempts']:.1f}) | {r['holds']:.1f} | {r['reused']:.1f} | "
            f"{r['planning_s']:.3f} | {r['execution_s']:.3f} | {r['total_s']:.3f} | "
            f"{r['planning_share']:.0%} | {r['median_share']:.0%} | "
            f"{r['missions_within_30pct']}/{r['missions']} | {r['action_ms_for_30pct']:.1f} |"
        )
    out("")
    for r in section["rows"]:
        if r["planners_won"]:
            wins = ", ".join(f"{k} {v}" for k, v in sorted(r["planners_won"].items()))
            out(f"* {r['problem']}, {r['policy']}: plans found by {wins}")
    out("")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--quick", action="store_true", help="blocks only")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    from plan_bridge.planning.planner import get_planner

    planner = get_planner("fast-downward")
    planner.warm_up()
    section = recovery_section(planner, args.seeds, args.fail_rate, args.quick)
    print_section(section)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(section, fh, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
