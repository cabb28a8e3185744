"""Benchmark of temporal plans: plan + dispatch against TAMER alone, jitter, 100 actions.

Usage::

    .venv/bin/python benchmarks/temporal_bench.py                 # about 30 s
    .venv/bin/python benchmarks/temporal_bench.py --quick         # a few seconds
    .venv/bin/python benchmarks/temporal_bench.py --json out.json

Sections (every ratio is computed from numbers measured in the same run):

(a) **overhead**: the night-patrol problem of tests/plan_bridge/data/temporal (durative
    actions that must overlap, numeric fluents, a numeric goal; TAMER accepts it) is
    planned and dispatched by plan_bridge: ``load_task_from_text`` (which primes the
    worker's parse, as ``plan-bridge run`` does), then an :class:`Executive` with
    ``--planner tamer`` (a warm worker), no-op skills and ``time_scale`` 0. Against it,
    in the same process and trials alternating: TAMER alone through unified-planning
    (``PDDLReader().parse_problem`` + ``OneshotPlanner(name="tamer").solve``). The aim
    compares ``plan + dispatch`` with the direct ``solve``; the whole job (our load
    included) is also compared with the direct ``parse + solve``. Each trial's problem
    text gets a unique comment, so nothing is reused from an earlier trial's parse. The
    first trial of each side (imports, worker start, TAMER's first load) is shown apart
    and left out of the medians.
(b) **dispatch jitter**: plans dispatched with no-op skills at ``time_scale`` 0.01 and
    0.05 wall seconds per plan second (the timeline is played): for each step, actual
    start (since the dispatch began) minus planned start x time_scale, in ms. Two plans:
    the timed courier's 14-step plan (the one Kairos finds for domains/timed_courier
    p01: a door held while a robot passes, overlapping actions) and the generated patrol
    plan of (c).
(c) **100-action temporal plan**: a generated patrol domain (benchmarks/data/
    temporal_patrol.pddl: R robots, each driving a chain of waypoints, every move
    adding to one shared ``(visits)`` counter, so every pair of moves interferes and the
    temporal network is dense); the plan is built directly (robot k's i-th move starts
    at ``i + k/R``, duration 1), checked valid by the model, then compiled
    (``compile_temporal``: grounding, the start and end precedence networks, states)
    and dispatched at ``time_scale`` 0. Per-step overhead = dispatch time / steps. The
    same steps without times, compiled and run as a sequential plan, are shown for
    comparison.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import json
import statistics
import sys
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import smach  # noqa: E402

PATROL = ROOT / "tests" / "plan_bridge" / "data" / "temporal"
COURIER = ROOT / "domains" / "timed_courier"
PATROL_DOMAIN = ROOT / "benchmarks" / "data" / "temporal_patrol.pddl"

#: The plan Kairos returns for domains/timed_courier p01 (start, action, duration).
COURIER_PLAN = (
    (0.0, "drive courier depot hall", 6.0),
    (6.0, "hold-door courier hall lab", 5.0),
    (6.0, "pass-door helper hall lab", 3.0),
    (9.0, "grab helper box1 lab", 2.0),
    (11.001, "hand-over helper box1 lab", 2.0),
    (11.001, "hold-door helper lab hall", 5.0),
    (11.001, "pass-door courier hall lab", 3.0),
    (14.001, "grab courier box1 lab", 2.0),
    (16.002, "hold-door courier lab hall", 5.0),
    (16.002, "pass-door helper lab hall", 3.0),
    (21.003, "hold-door helper hall lab", 5.0),
    (21.003, "pass-door courier lab hall", 3.0),
    (24.004, "drive courier hall depot", 6.0),
    (30.004, "hand-over courier box1 depot", 2.0),
)

AIMS = {"overhead_ratio": 1.5, "jitter_p95_ms": 5.0}


def progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


def percentile(values: list[float], share: float) -> float:
    ordered = sorted(values)
    if not ordered:
        return float("nan")
    return ordered[min(len(ordered) - 1, round(share * (len(ordered) - 1)))]


class NoOp(smach.State):
    """A skill that succeeds at once."""

    def __init__(self, *args: str) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])

    def execute(self, ud: smach.UserData) -> str:
        return "succeeded"


def noop_skills(task: Any) -> Any:
    from plan_bridge.skills.registry import SkillRegistry

    skills = SkillRegistry()
    for action in task.actions:
        skills.add(action, NoOp)
    return skills


@contextlib.contextmanager
def quiet_up() -> Iterator[None]:
    from unified_planning.shortcuts import get_environment

    get_environment().credits_stream = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


# -- (a) overhead against TAMER alone ----------------------------------------------------------


def direct_tamer(trial: int) -> dict[str, float]:
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import OneshotPlanner

    domain = (PATROL / "domain.pddl").read_text()
    problem = (PATROL / "problem.pddl").read_text() + f"\n; direct trial {trial}\n"
    with quiet_up():
        started = time.perf_counter()
        up_problem = PDDLReader().parse_problem_string(domain, problem)
        parsed = time.perf_counter()
        with OneshotPlanner(name="tamer") as planner:
            result = planner.solve(up_problem)
        done = time.perf_counter()
    assert result.plan is not None, f"TAMER found no plan: {result.status}"
    return {"parse_s": parsed - started, "solve_s": done - parsed, "total_s": done - started}


def ours_tamer(trial: int, planner: Any) -> dict[str, float]:
    from plan_bridge.pddl.task import load_task_from_text

    domain = (PATROL / "domain.pddl").read_text()
    problem = (PATROL / "problem.pddl").read_text() + f"\n; our trial {trial}\n"
    started = time.perf_counter()
    task = load_task_from_text(domain, problem, prime=planner.pool)
    loaded = time.perf_counter()
    first = execute(task, planner)
    done = time.perf_counter()
    again = execute(task, planner)
    return {
        "load_s": loaded - started,
        "plan_dispatch_s": done - loaded,
        "planning_s": first["planning_s"],
        "dispatch_s": first["dispatch_s"],
        "total_s": done - started,
        "parsed_plan_dispatch_s": again["total_s"],
        "parsed_planning_s": again["planning_s"],
    }


def execute(task: Any, planner: Any) -> dict[str, float]:
    """Plan and dispatch ``task`` with no-op skills at ``time_scale`` 0."""
    from plan_bridge.execution.executive import Executive

    started = time.perf_counter()
    executive = Executive(task, noop_skills(task), planner)
    executive.time_scale = 0.0
    outcome = executive.execute()
    done = time.perf_counter()
    report = executive.report
    assert outcome == "succeeded" and report.goal_reached, report.explanation
    return {
        "total_s": done - started,
        "planning_s": report.planning_time_s,
        "dispatch_s": report.execution_time_s,
    }


def overhead_section(trials: int) -> dict[str, Any]:
    from plan_bridge.planning.planner import get_planner

    planner = get_planner("tamer")
    planner.warm_up()
    first_direct = direct_tamer(0)
    first_ours = ours_tamer(0, planner)
    direct: list[dict[str, float]] = []
    ours: list[dict[str, float]] = []
    for trial in range(1, trials + 1):
        # Alternate, so that drift of a shared machine hits both alike.
        direct.append(direct_tamer(trial))
        ours.append(ours_tamer(trial, planner))

    def med(rows: list[dict[str, float]], key: str) -> float:
        return median([row[key] for row in rows])

    solve, parse = med(direct, "solve_s"), med(direct, "parse_s")
    plan_dispatch = med(ours, "plan_dispatch_s")
    total = med(ours, "total_s")
    return {
        "problem": "tests/plan_bridge/data/temporal (night patrol)",
        "trials": trials,
        "direct_parse_s": parse,
        "direct_solve_s": solve,
        "direct_total_s": med(direct, "total_s"),
        "ours_load_s": med(ours, "load_s"),
        "ours_planning_s": med(ours, "planning_s"),
        "ours_dispatch_s": med(ours, "dispatch_s"),
        "ours_plan_dispatch_s": plan_dispatch,
        "ours_total_s": total,
        "ours_parsed_plan_dispatch_s": med(ours, "parsed_plan_dispatch_s"),
        "ours_parsed_planning_s": med(ours, "parsed_planning_s"),
        "ratio_plan_dispatch_to_solve": plan_dispatch / solve,
        "ratio_parsed_to_solve": med(ours, "parsed_plan_dispatch_s") / solve,
        "ratio_total_to_parse_solve": total / med(direct, "total_s"),
        "first_direct_total_s": first_direct["total_s"],
        "first_ours_total_s": first_ours["total_s"],
    }


# -- the generated patrol ----------------------------------------------------------------------


def patrol_problem(robots: int, moves: int) -> str:
    """``robots`` robots, each with a chain of ``moves`` links to drive."""
    objects, init, goal = [], [], []
    for k in range(1, robots + 1):
        points = [f"w{k}_{i}" for i in range(moves + 1)]
        objects.append(f"r{k} - robot " + " ".join(points) + " - waypoint")
        init.append(f"(at r{k} w{k}_0)")
        init.extend(f"(link {a} {b})" for a, b in itertools.pairwise(points))
        goal.append(f"(visited {points[-1]})")
    return (
        "(define (problem patrol)\n  (:domain temporal-patrol)\n"
        f"  (:objects {' '.join(objects)})\n"
        f"  (:init {' '.join(init)} (= (visits) 0))\n"
        f"  (:goal (and {' '.join(goal)} (>= (visits) {robots * moves}))))\n"
    )


def patrol(steps: int, robots: int = 4) -> tuple[Any, list[Any]]:
    """The patrol task and a valid plan of ``steps`` moves (rounded to ``robots``)."""
    from plan_bridge.pddl.task import load_task_from_text
    from plan_bridge.planning.planner import PlanStep

    robots = max(1, min(robots, steps))
    moves = max(1, steps // robots)
    task = load_task_from_text(PATROL_DOMAIN.read_text(), patrol_problem(robots, moves))
    plan = [
        PlanStep("move", (f"r{k}", f"w{k}_{i}", f"w{k}_{i + 1}"), i + (k - 1) / robots, 1.0)
        for i in range(moves)
        for k in range(1, robots + 1)
    ]
    return task, plan


def courier() -> tuple[Any, list[Any]]:
    from plan_bridge.pddl.task import load_task
    from plan_bridge.planning.planner import PlanStep

    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    plan = []
    for start, text, duration in COURIER_PLAN:
        name, *arguments = text.split()
        plan.append(PlanStep(name, tuple(arguments), start, duration))
    return task, plan


def dispatch_once(task: Any, plan: list[Any], time_scale: float) -> tuple[Any, float, float]:
    """Compile and run ``plan`` with no-op skills: (dispatch, compile s, dispatch s)."""
    from plan_bridge.belief import Belief
    from plan_bridge.execution.semantics import ActionModel
    from plan_bridge.execution.temporal import compile_temporal

    model = ActionModel(task)  # fresh: grounding is part of compiling
    belief = Belief(task.initial_facts, model.initial_values())
    started = time.perf_counter()
    compiled = compile_temporal(plan, noop_skills(task), model, belief, time_scale=time_scale)
    compiled_at = time.perf_counter()
    outcome = compiled.machine.execute(smach.UserData())
    done = time.perf_counter()
    assert outcome == "succeeded", outcome
    assert model.goal_holds(belief.facts), "the plan ran but the goal does not hold"
    return compiled.machine, compiled_at - started, done - compiled_at


# -- (b) jitter --------------------------------------------------------------------------------


def jitter_section(scales: list[float], trials: int, steps: int) -> list[dict[str, Any]]:
    rows = []
    plans = {"timed courier p01": courier(), f"patrol ({steps} steps)": patrol(steps)}
    for name, (task, plan) in plans.items():
        dispatch_once(task, plan, scales[0])  # warm-up: the first dispatch of a plan
        for scale in scales:
            late: list[float] = []
            for _ in range(trials):
                dispatch, _, _ = dispatch_once(task, plan, scale)
                for j, state in enumerate(dispatch._states.values()):
                    actual = state.timing.actual_start
                    assert actual is not None
                    late.append((actual - dispatch.planned_start[j] * scale) * 1000.0)
            rows.append(
                {
                    "plan": name,
                    "steps": len(plan),
                    "time_scale": scale,
                    "starts": len(late),
                    "median_ms": median(late),
                    "p95_ms": percentile(late, 0.95),
                    "max_ms": max(late),
                    "min_ms": min(late),
                }
            )
    return rows


# -- (c) 100-action plan -----------------------------------------------------------------------


def hundred_section(steps: int, trials: int) -> dict[str, Any]:
    from plan_bridge.belief import Belief
    from plan_bridge.execution.compile import compile_plan
    from plan_bridge.execution.semantics import ActionModel
    from plan_bridge.planning.planner import PlanStep

    task, plan = patrol(steps)
    model = ActionModel(task)
    check = model.check_plan(plan, Belief(task.initial_facts, model.initial_values()).facts)
    assert check.valid, check.explain()
    compile_times, dispatch_times = [], []
    for _ in range(trials):
        _, compile_s, dispatch_s = dispatch_once(task, plan, 0.0)
        compile_times.append(compile_s)
        dispatch_times.append(dispatch_s)
    sequential = [PlanStep(s.action, s.arguments) for s in plan]
    seq_compile, seq_run = [], []
    for _ in range(trials):
        model = ActionModel(task)
        belief = Belief(task.initial_facts, model.initial_values())
        started = time.perf_counter()
        compiled = compile_plan(sequential, noop_skills(task), model, belief)
        compiled_at = time.perf_counter()
        outcome = compiled.machine.execute(smach.UserData())
        done = time.perf_counter()
        assert outcome == "succeeded", outcome
        seq_compile.append(compiled_at - started)
        seq_run.append(done - compiled_at)
    dispatch_s = median(dispatch_times)
    return {
        "steps": len(plan),
        "makespan": max((s.start or 0.0) + (s.duration or 0.0) for s in plan),
        "compile_s": median(compile_times),
        "dispatch_s": dispatch_s,
        "per_step_ms": dispatch_s / len(plan) * 1000.0,
        "sequential_compile_s": median(seq_compile),
        "sequential_run_s": median(seq_run),
    }


# -- report ------------------------------------------------------------------------------------


def verdict(ok: bool) -> str:
    return "met" if ok else "MISSED"


def print_report(results: dict[str, Any]) -> None:
    a = results["overhead"]
    print(f"(a) plan + dispatch against TAMER alone: {a['problem']}, {a['trials']} trials")
    print(f"    TAMER alone: parse {a['direct_parse_s']:.3f} s, solve {a['direct_solve_s']:.3f} s")
    print(
        f"    plan_bridge: load {a['ours_load_s']:.3f} s, planning {a['ours_planning_s']:.3f} s, "
        f"dispatch {a['ours_dispatch_s'] * 1000:.1f} ms, "
        f"plan + dispatch {a['ours_plan_dispatch_s']:.3f} s"
    )
    print(
        f"    the same task again (the worker holds its parse): plan + dispatch "
        f"{a['ours_parsed_plan_dispatch_s']:.3f} s (planning {a['ours_parsed_planning_s']:.3f} s)"
    )
    aim = AIMS["overhead_ratio"]
    first, parsed = a["ratio_plan_dispatch_to_solve"], a["ratio_parsed_to_solve"]
    print(
        f"    plan + dispatch / TAMER solve: first plan of a new text {first:.2f}x "
        f"(the worker parses it too), parsed {parsed:.2f}x "
        f"(aim <= {aim}x: {verdict(parsed <= aim)})"
    )
    print(
        f"    whole job (load + plan + dispatch) / (UP parse + TAMER solve): "
        f"{a['ratio_total_to_parse_solve']:.2f}x"
    )
    print(
        f"    first trial (left out): TAMER alone {a['first_direct_total_s']:.3f} s, "
        f"plan_bridge {a['first_ours_total_s']:.3f} s"
    )
    print("(b) dispatch jitter: actual - planned start, no-op skills")
    print(f"    {'plan':<22} {'scale':>6} {'starts':>7} {'median':>8} {'p95':>8} {'max':>8}")
    for row in results["jitter"]:
        print(
            f"    {row['plan']:<22} {row['time_scale']:>6g} {row['starts']:>7} "
            f"{row['median_ms']:>6.2f}ms {row['p95_ms']:>6.2f}ms {row['max_ms']:>6.2f}ms"
        )
    worst = max(row["p95_ms"] for row in results["jitter"])
    print(
        f"    worst p95: {worst:.2f} ms "
        f"(aim <= {AIMS['jitter_p95_ms']:g} ms: {verdict(worst <= AIMS['jitter_p95_ms'])})"
    )
    c = results["hundred"]
    print(f"(c) {c['steps']}-action temporal plan (patrol, makespan {c['makespan']:g} plan s)")
    print(
        f"    compile {c['compile_s'] * 1000:.1f} ms, dispatch {c['dispatch_s'] * 1000:.1f} ms, "
        f"per step {c['per_step_ms']:.3f} ms"
    )
    print(
        f"    the same steps as a sequential plan: compile "
        f"{c['sequential_compile_s'] * 1000:.1f} ms, run {c['sequential_run_s'] * 1000:.1f} ms"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--quick", action="store_true", help="few trials, small plans")
    parser.add_argument("--trials", type=int, default=None, help="trials per measure")
    parser.add_argument("--steps", type=int, default=None, help="steps of the patrol plan")
    parser.add_argument(
        "--scales",
        default="0.01,0.05",
        help="time scales of the jitter runs, comma-separated (default 0.01,0.05)",
    )
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    args = parser.parse_args(argv)
    trials = args.trials or (2 if args.quick else 7)
    steps = args.steps or (20 if args.quick else 100)
    if trials < 1 or steps < 1:
        parser.error("--trials and --steps must be 1 or more")
    try:
        scales = [float(s) for s in args.scales.split(",") if s.strip()]
    except ValueError:
        parser.error(f"--scales: comma-separated numbers expected, got {args.scales!r}")
    if not scales or any(s <= 0 for s in scales):
        parser.error("--scales: one or more time scales above 0 expected")
    progress("(a) plan + dispatch against TAMER alone...")
    results: dict[str, Any] = {"overhead": overhead_section(trials)}
    progress("(b) dispatch jitter...")
    results["jitter"] = jitter_section(scales, min(trials, 3), steps)
    progress(f"(c) {steps}-action temporal plan...")
    results["hundred"] = hundred_section(steps, trials)
    print_report(results)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
