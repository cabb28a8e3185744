"""Benchmark of plan_bridge: our layer's overhead, compile/execute, replanning, start-up.

Usage::

    .venv/bin/python benchmarks/plan_bridge_bench.py --trials 2 # full run (~25 min here)
    .venv/bin/python benchmarks/plan_bridge_bench.py --quick    # smoke test (~1 min)
    .venv/bin/python benchmarks/plan_bridge_bench.py --json results.json

Sections (every ratio is computed from numbers measured in the same run):

(a) **overhead**: for every problem of ../shared/pddl-bench that unified-planning
    parses, a ``plan-bridge run``-equivalent in this process (``load_target`` on the
    files, symbolic skills, their check, an :class:`Executive` with a warm worker pool,
    no failures) against a direct UP solve of the same files in the same process
    (``PDDLReader().parse_problem`` + ``OneshotPlanner(name="fast-downward").solve``).
    ``overhead = ours_total - direct_total`` (direct_total = UP parse + UP solve) is
    what our layer adds to the job a UP user does by hand, reported as a % of the
    direct solve time (the planning time). ``layer`` = ours_total - the engine's time
    inside our worker (everything that is not the engine: both parses, checks,
    compile, execute, bookkeeping), as a % of that engine time, is also shown. Each
    trial's problem file gets a unique trailing comment, so the worker parses it like
    a fresh ``plan-bridge run`` would (no reuse of an earlier trial's parse).
(b) **1000-action plan**: a synthetic 1000-step plan (a chain of moves in a generated
    domain) compiled into a StateMachine and executed with no-op skills (precondition
    checks and belief updates on), compile and execute timed separately.
(c) **replanning**: an Executive (policy ``replan-only``) whose world fails one action
    in the middle of the plan; latency = failed step finished -> new plan computed.
    ``cold`` = the same state planned by a fresh planner (new worker process: start,
    parse, solve); ``warm re-parse`` = the warm worker given new PDDL text (what a replan
    cost before workers kept parsed problems).
(d) **start-up**: ``plan-bridge --help`` and bad-input errors, as subprocesses.
(e) **scaling**: generated chain problems of growing size: plan, compile, execute and
    replan times; plotted to docs/images/plan_bridge_scaling.png (needs matplotlib).
(f) **missions with faults**: per recovery policy (no repair, the recovery before
    issue 19, the default, the default with a shared plan cache), planner calls,
    replans, repairs, held and reused plans and the planning share of the mission
    time; see benchmarks/plan_bridge_recovery.py.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from plan_bridge_recovery import print_section, recovery_section  # noqa: E402

RECOVERY_TARGET_PROBLEM = "blocks/probBLOCKS-14-0"

BENCH = (ROOT / ".." / "shared" / "pddl-bench").resolve()
PLAN_BRIDGE = Path(sys.executable).with_name("plan-bridge")
PNG = ROOT / "docs" / "images" / "plan_bridge_scaling.png"

TARGETS = {
    "overhead_pct": 10.0,
    "compile_execute_1000_s": 0.5,
    "replan_ratio": 0.3,
    "help_s": 0.3,
    "bad_input_s": 1.5,
}


def progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


@contextlib.contextmanager
def in_temp_dir() -> Iterator[Path]:
    home = os.getcwd()
    folder = Path(tempfile.mkdtemp(prefix="plan-bridge-bench-"))
    os.chdir(folder)
    try:
        yield folder
    finally:
        os.chdir(home)
        shutil.rmtree(folder, ignore_errors=True)


# -- the benchmark problems -------------------------------------------------------------


def bench_problems(quick: bool) -> tuple[list[tuple[Path, Path]], list[str]]:
    """Parseable (domain, problem) pairs and the names of the ones UP cannot parse."""
    from plan_bridge.errors import PddlError
    from plan_bridge.pddl.task import load_task

    pairs, skipped = [], []
    for folder in sorted(p for p in BENCH.iterdir() if p.is_dir()):
        domain = folder / "domain.pddl"
        problems = sorted(p for p in folder.glob("*.pddl") if p.name != "domain.pddl")
        try:
            load_task(domain, problems[0])
        except PddlError as exc:
            skipped.append(f"{folder.name} ({type(exc).__name__})")
            continue
        pairs.extend((domain, p) for p in problems)
    if quick:
        wanted = {"gripper/prob01", "blocks/probBLOCKS-8-0", "miconic/s3-0"}
        pairs = [(d, p) for d, p in pairs if f"{d.parent.name}/{p.stem}" in wanted]
    return pairs, skipped


def name_of(problem: Path) -> str:
    return f"{problem.parent.name}/{problem.stem}"


# -- (a) overhead -------------------------------------------------------------------------


def direct_solve(domain: Path, problem: Path) -> dict[str, float]:
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import OneshotPlanner

    with in_temp_dir(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        started = time.perf_counter()
        up_problem = PDDLReader().parse_problem(str(domain), str(problem))
        parsed = time.perf_counter()
        with OneshotPlanner(name="fast-downward") as planner:
            result = planner.solve(up_problem, timeout=300)
        done = time.perf_counter()
    assert result.plan is not None, f"direct UP found no plan for {problem}"
    return {"parse_s": parsed - started, "solve_s": done - parsed, "total_s": done - started}


def ours_run(domain: Path, problem: Path, trial: int, planner: Any) -> dict[str, float]:
    """What ``plan-bridge run DOMAIN --problem PROBLEM --fail-rate 0`` does, in process."""
    from plan_bridge.execution.events import PlanComputed
    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.missions.mission import load_target

    with tempfile.TemporaryDirectory(prefix="plan-bridge-bench-") as folder:
        copy = Path(folder) / problem.name
        copy.write_text(problem.read_text() + f"\n; benchmark trial {trial}\n")
        engine_time: list[float] = []
        started = time.perf_counter()
        target = load_target(domain, copy, prime=planner.pool)
        loaded = time.perf_counter()
        setup = target.setup(seed=trial, fail_rate=0.0)
        problems = setup.skills.check(target.task)
        assert not problems, problems
        executive = Executive(
            target.task, setup.skills, planner, policy=replace(ReplanPolicy(), max_replans=10)
        )
        executive.add_listener(
            lambda e: engine_time.append(e.planning_time_s) if isinstance(e, PlanComputed) else None
        )
        outcome = executive.execute()
        done = time.perf_counter()
    report = executive.report
    assert outcome == "succeeded" and report.goal_reached, (problem, report.explanation)
    return {
        "load_s": loaded - started,
        "planning_s": report.planning_time_s,
        "execute_s": report.execution_time_s,
        "total_s": done - started,
        "plan_length": float(len(report.final_plan)),
    }


def engine_time_of(planner: Any, domain: Path, problem: Path, trial: int) -> float:
    """The engine's own time inside our worker for a fresh parse of ``problem``."""
    from plan_bridge.pddl.task import load_task_from_text

    task = load_task_from_text(
        domain.read_text(), problem.read_text() + f"\n; engine trial {trial}\n"
    )
    result = planner.solve(task, timeout=300)
    assert result.solved
    return float(result.engine_time_s)


def overhead_section(pairs: list[tuple[Path, Path]], trials: int, planner: Any) -> dict[str, Any]:
    rows: dict[str, dict[str, list[float]]] = {name_of(p): {} for _, p in pairs}
    for trial in range(trials):
        for domain, problem in pairs:
            name = name_of(problem)
            progress(f"  (a) trial {trial + 1}/{trials}: {name}")
            samples = rows[name]
            # Alternate the order so that neither side always runs second.
            first_ours = (trial + len(samples)) % 2 == 0
            for side in ("ours", "direct") if first_ours else ("direct", "ours"):
                if side == "ours":
                    result = ours_run(domain, problem, trial, planner)
                else:
                    result = direct_solve(domain, problem)
                for key, value in result.items():
                    samples.setdefault(f"{side}_{key}", []).append(value)
            samples.setdefault("engine_s", []).append(
                engine_time_of(planner, domain, problem, trial)
            )
    table = []
    for name, samples in rows.items():
        med = {key: median(values) for key, values in samples.items()}
        direct_total = med["direct_total_s"]
        ours_total = med["ours_total_s"]
        table.append(
            {
                "problem": name,
                "plan_length": int(med["ours_plan_length"]),
                "direct_parse_s": med["direct_parse_s"],
                "direct_solve_s": med["direct_solve_s"],
                "direct_total_s": direct_total,
                "ours_load_s": med["ours_load_s"],
                "ours_planning_s": med["ours_planning_s"],
                "ours_execute_s": med["ours_execute_s"],
                "ours_total_s": ours_total,
                "engine_s": med["engine_s"],
                "overhead_s": ours_total - direct_total,
                "overhead_pct": 100.0 * (ours_total - direct_total) / med["direct_solve_s"],
                "layer_s": ours_total - med["engine_s"],
                "layer_pct": 100.0 * (ours_total - med["engine_s"]) / med["engine_s"],
            }
        )
    return {
        "rows": table,
        "median_overhead_pct": median([r["overhead_pct"] for r in table]),
        "median_layer_pct": median([r["layer_pct"] for r in table]),
        "median_overhead_s": median([r["overhead_s"] for r in table]),
        "median_execute_s": median([r["ours_execute_s"] for r in table]),
    }


# -- generated chain domain (sections b and e) -------------------------------------------

CHAIN_DOMAIN = """\
(define (domain chain)
  (:requirements :strips :typing)
  (:types node)
  (:predicates (at ?n - node) (link ?a ?b - node) (visited ?n - node))
  (:action move
    :parameters (?a ?b - node)
    :precondition (and (at ?a) (link ?a ?b))
    :effect (and (at ?b) (visited ?b) (not (at ?a)))))
"""


def chain_problem(nodes: int, tag: str = "") -> str:
    names = [f"n{i}" for i in range(nodes)]
    links = " ".join(f"(link {a} {b})" for a, b in itertools.pairwise(names))
    return (
        f"(define (problem chain-{nodes}) (:domain chain)\n"
        f"  (:objects {' '.join(names)} - node)\n"
        f"  (:init (at n0) {links})\n"
        f"  (:goal (and (at {names[-1]}))))\n"
        f"; {tag}\n"
    )


def chain_task(nodes: int, tag: str = "") -> Any:
    from plan_bridge.pddl.task import load_task_from_text

    return load_task_from_text(CHAIN_DOMAIN, chain_problem(nodes, tag))


# -- (b) 1000-action plan -------------------------------------------------------------------


def thousand_section(trials: int) -> dict[str, Any]:
    import smach
    from plan_bridge.belief import Belief
    from plan_bridge.execution.compile import compile_plan
    from plan_bridge.execution.semantics import ActionModel
    from plan_bridge.planning.planner import PlanStep
    from plan_bridge.skills.registry import SkillRegistry

    class NoOp(smach.State):
        def __init__(self, *args: str) -> None:
            super().__init__(outcomes=["succeeded", "aborted", "preempted"])

        def execute(self, ud: smach.UserData) -> str:
            return "succeeded"

    steps = 1000
    task = chain_task(steps + 1)
    plan = [PlanStep("move", (f"n{i}", f"n{i + 1}")) for i in range(steps)]
    skills = SkillRegistry()
    skills.add("move", NoOp)
    compile_times, execute_times = [], []
    for _ in range(trials):
        model = ActionModel(task)  # fresh: grounding the 1000 steps is part of compiling
        belief = Belief(task.initial_facts)
        started = time.perf_counter()
        compiled = compile_plan(plan, skills, model, belief)
        compiled_at = time.perf_counter()
        outcome = compiled.machine.execute(smach.UserData())
        done = time.perf_counter()
        assert outcome == "succeeded" and ("at", f"n{steps}") in belief
        compile_times.append(compiled_at - started)
        execute_times.append(done - compiled_at)
    compile_s, execute_s = median(compile_times), median(execute_times)
    return {
        "steps": steps,
        "compile_s": compile_s,
        "execute_s": execute_s,
        "total_s": compile_s + execute_s,
        "compile_min_s": min(compile_times),
        "execute_min_s": min(execute_times),
    }


# -- (c) replanning latency -----------------------------------------------------------------


def replan_once(task: Any, planner: Any) -> dict[str, Any]:
    """Run ``task`` with one failure in the middle; time the replan and save the state."""
    from plan_bridge.execution.events import ExecutiveDecision, PlanComputed, StepFinished
    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
    from plan_bridge.planning.planner import PlanStep

    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    state: dict[str, Any] = {"fail_at": None, "calls": 0}
    perform = world.perform

    def perform_failing_once(step: PlanStep) -> Any:
        state["calls"] += 1
        if state["calls"] == state["fail_at"]:
            return False, []  # the action had no effect
        return perform(step)

    world.perform = perform_failing_once  # type: ignore[method-assign]
    executive = Executive(task, skills, planner, policy=ReplanPolicy.named("replan-only"))

    def listen(event: Any) -> None:
        now = time.perf_counter()
        if isinstance(event, PlanComputed):
            if state["fail_at"] is None:
                state["fail_at"] = max(1, (len(event.steps) + 1) // 2)
                state["plan_length"] = len(event.steps)
            elif event.reason.startswith("replan"):
                state["replanned_at"] = now
                state["replan_planning_s"] = event.planning_time_s
        elif isinstance(event, StepFinished) and event.outcome == "aborted":
            state["failed_at"] = now
        elif isinstance(event, ExecutiveDecision) and event.decision == "replan":
            state["belief"] = executive.belief.facts

    executive.add_listener(listen)
    assert executive.execute() == "succeeded", executive.report.explanation
    assert executive.report.replans == 1, executive.report.decisions
    return {
        "latency_s": state["replanned_at"] - state["failed_at"],
        "replan_planning_s": state["replan_planning_s"],
        "belief": state["belief"],
        "plan_length": state["plan_length"],
    }


def cold_replan(task: Any, belief: Any) -> float:
    """A fresh planner (new worker process: start, parse, solve) for the same state."""
    from plan_bridge.planning.planner import UPPlanner
    from plan_bridge.planning.worker import WorkerPool

    started = time.perf_counter()
    pool = WorkerPool(max_workers=1)
    try:
        result = UPPlanner("fast-downward", pool=pool).solve(
            task, timeout=300, initial_state=belief
        )
        elapsed = time.perf_counter() - started
    finally:
        pool.close()
    assert result.solved
    return elapsed


def warm_reparse(task: Any, belief: Any, planner: Any) -> float:
    """The warm worker given new PDDL text for the state (parsed again)."""
    started = time.perf_counter()
    derived = task.with_initial_state(belief)
    # A unique comment: the worker must not find this text among its parsed ones.
    derived = replace(derived, problem_text=f"{derived.problem_text}\n; {time.time_ns()}\n")
    result = planner.solve(derived, timeout=300)
    elapsed = time.perf_counter() - started
    assert result.solved and not result.problem_reused
    return elapsed


def replan_section(pairs: list[tuple[Path, Path]], trials: int, planner: Any) -> dict[str, Any]:
    from plan_bridge.pddl.task import load_task

    table = []
    for domain, problem in pairs:
        name = name_of(problem)
        progress(f"  (c) {name}")
        task = load_task(domain, problem)
        samples: dict[str, list[float]] = {}
        length = 0
        for _ in range(trials):
            run = replan_once(task, planner)
            length = run["plan_length"]
            samples.setdefault("latency_s", []).append(run["latency_s"])
            samples.setdefault("replan_planning_s", []).append(run["replan_planning_s"])
            samples.setdefault("cold_s", []).append(cold_replan(task, run["belief"]))
            samples.setdefault("warm_reparse_s", []).append(
                warm_reparse(task, run["belief"], planner)
            )
        med = {key: median(values) for key, values in samples.items()}
        table.append(
            {
                "problem": name,
                "plan_length": length,
                **med,
                "ratio": med["latency_s"] / med["cold_s"],
                "ratio_vs_warm_reparse": med["latency_s"] / med["warm_reparse_s"],
            }
        )
    return {
        "rows": table,
        "median_ratio": median([r["ratio"] for r in table]),
        "max_ratio": max(r["ratio"] for r in table),
        "median_ratio_vs_warm_reparse": median([r["ratio_vs_warm_reparse"] for r in table]),
        "median_latency_s": median([r["latency_s"] for r in table]),
        "median_cold_s": median([r["cold_s"] for r in table]),
    }


# -- (d) start-up ---------------------------------------------------------------------------


def startup_section(runs: int) -> dict[str, Any]:
    folder = Path(tempfile.mkdtemp(prefix="plan-bridge-bench-"))
    try:
        unbalanced = folder / "unbalanced.pddl"
        unbalanced.write_text("(define (problem p) (:domain gripper-strips)\n  (:init (room a)\n")
        gripper_domain = (BENCH / "gripper" / "domain.pddl").read_text()
        misspelt = folder / "misspelt.pddl"
        misspelt.write_text(gripper_domain.replace(":effect", ":efect", 1))
        malformed = folder / "malformed.pddl"
        malformed.write_text(
            re.sub(r":parameters\s*\(\?from \?to\)", ":parameters ?from", gripper_domain)
        )
        gripper = BENCH / "gripper"
        cases: list[tuple[str, list[str], int]] = [
            ("plan-bridge --help", ["--help"], 0),
            (
                "plan missing file",
                ["plan", str(folder / "missing.pddl"), str(folder / "missing.pddl")],
                2,
            ),
            (
                "plan unbalanced parentheses",
                ["plan", str(gripper / "domain.pddl"), str(unbalanced)],
                2,
            ),
            (
                "plan unsupported (either ...) (storage)",
                [
                    "plan",
                    str(BENCH / "storage" / "domain.pddl"),
                    str(BENCH / "storage" / "p01.pddl"),
                ],
                2,
            ),
            (
                "plan misspelt keyword (`:efect`)",
                ["plan", str(misspelt), str(gripper / "prob01.pddl")],
                2,
            ),
            (
                "plan syntax error found by UP's parser (`:parameters ?from`)",
                ["plan", str(malformed), str(gripper / "prob01.pddl")],
                2,
            ),
            (
                "run unknown planner",
                [
                    "run",
                    str(gripper / "domain.pddl"),
                    "--problem",
                    str(gripper / "prob01.pddl"),
                    "--planner",
                    "nope",
                ],
                2,
            ),
        ]
        rows = []
        for label, args, expected in cases:
            times = []
            for _ in range(runs):
                started = time.perf_counter()
                done = subprocess.run(
                    [str(PLAN_BRIDGE), *args], capture_output=True, text=True, check=False
                )
                times.append(time.perf_counter() - started)
                assert done.returncode == expected, (label, done.returncode, done.stderr)
                assert "Traceback" not in done.stderr, done.stderr
            target = TARGETS["help_s"] if label.endswith("--help") else TARGETS["bad_input_s"]
            rows.append(
                {
                    "case": label,
                    "median_s": median(times),
                    "min_s": min(times),
                    "max_s": max(times),
                    "target_s": target,
                }
            )
        return {"rows": rows, "runs": runs}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# -- (e) scaling ------------------------------------------------------------------------------


def scaling_section(sizes: list[int], planner: Any) -> dict[str, Any]:
    import smach
    from plan_bridge.belief import Belief
    from plan_bridge.execution.compile import compile_plan
    from plan_bridge.execution.events import PlanComputed
    from plan_bridge.execution.executive import Executive
    from plan_bridge.execution.semantics import ActionModel
    from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills

    rows = []
    for nodes in sizes:
        progress(f"  (e) chain of {nodes} nodes")
        task = chain_task(nodes, tag=f"scaling {time.time()}")
        world = SimulatedWorld(task)
        executive = Executive(task, symbolic_skills(world), planner)
        plans: list[Any] = []
        executive.add_listener(
            lambda e, plans=plans: plans.append(e) if isinstance(e, PlanComputed) else None
        )
        assert executive.execute() == "succeeded"
        plan_s = plans[0].planning_time_s
        plan = _steps(plans[0].steps)
        # Compile and execute separately (symbolic skills, a fresh world and belief).
        world = SimulatedWorld(task)
        belief = Belief(task.initial_facts)
        model = ActionModel(task)
        started = time.perf_counter()
        compiled = compile_plan(plan, symbolic_skills(world), model, belief)
        compiled_at = time.perf_counter()
        assert compiled.machine.execute(smach.UserData()) == "succeeded"
        done = time.perf_counter()
        replan = replan_once(task, planner)
        rows.append(
            {
                "nodes": nodes,
                "objects": len(task.objects),
                "plan_length": len(plan),
                "plan_s": plan_s,
                "compile_s": compiled_at - started,
                "execute_s": done - compiled_at,
                "replan_s": replan["latency_s"],
                "cold_replan_s": cold_replan(task, replan["belief"]),
            }
        )
    return {"rows": rows}


def _steps(texts: tuple[str, ...]) -> list[Any]:
    from plan_bridge.planning.planner import PlanStep

    steps = []
    for text in texts:
        words = text[1:-1].split()
        steps.append(PlanStep(words[0], tuple(words[1:])))
    return steps


def plot_scaling(rows: list[dict[str, Any]], path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        progress("  matplotlib is not installed: no plot (pip install matplotlib)")
        return False
    x = [r["plan_length"] for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    for key, label, style in (
        ("plan_s", "plan (warm worker, first parse)", "o-"),
        ("replan_s", "replan after one failure", "s-"),
        ("cold_replan_s", "cold re-plan (new worker)", "x--"),
        ("compile_s", "compile", "^-"),
        ("execute_s", "execute (symbolic skills)", "v-"),
    ):
        ax.plot(x, [r[key] for r in rows], style, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("plan length = objects - 1 (generated chain problems)")
    ax.set_ylabel("seconds")
    ax.set_title("plan_bridge scaling")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return True


# -- report -----------------------------------------------------------------------------------


def verdict(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def print_report(results: dict[str, Any]) -> None:
    out = print
    meta = results["machine"]
    out(
        f"# plan_bridge benchmark ({meta['cpus']} CPUs, {meta['python']}, load "
        f"{meta['load_before']} -> {meta['load_after']})\n"
    )
    if "overhead" in results:
        sec = results["overhead"]
        out(f"## (a) overhead vs direct UP (median of {results['trials']} trials per problem)\n")
        out(
            "| problem | plan | direct parse s | direct solve s | direct total s | ours total s "
            "| engine s | overhead s | overhead % of solve | layer % of engine |"
        )
        out("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for r in sec["rows"]:
            out(
                f"| {r['problem']} | {r['plan_length']} | {r['direct_parse_s']:.3f} | "
                f"{r['direct_solve_s']:.3f} | {r['direct_total_s']:.3f} | {r['ours_total_s']:.3f} | "
                f"{r['engine_s']:.3f} | {r['overhead_s']:+.3f} | {r['overhead_pct']:+.1f} | "
                f"{r['layer_pct']:+.1f} |"
            )
        out(
            f"\nmedian overhead: {sec['median_overhead_pct']:+.1f}% of the direct solve time "
            f"({sec['median_overhead_s']:+.3f} s); median layer cost: "
            f"{sec['median_layer_pct']:+.1f}% of the engine time\n"
        )
    if "thousand" in results:
        t = results["thousand"]
        out("## (b) 1000-action plan, no-op skills\n")
        out(
            f"compile {t['compile_s'] * 1000:.1f} ms, execute {t['execute_s'] * 1000:.1f} ms, "
            f"total {t['total_s'] * 1000:.1f} ms (min {t['compile_min_s'] * 1000:.1f} + "
            f"{t['execute_min_s'] * 1000:.1f} ms)\n"
        )
    if "replan" in results:
        sec = results["replan"]
        out("## (c) replanning latency after one injected failure\n")
        out(
            "| problem | plan | replan latency s | (planner call s) | cold re-plan s | "
            "warm re-parse s | latency / cold | latency / warm re-parse |"
        )
        out("|---|---:|---:|---:|---:|---:|---:|---:|")
        for r in sec["rows"]:
            out(
                f"| {r['problem']} | {r['plan_length']} | {r['latency_s']:.3f} | "
                f"{r['replan_planning_s']:.3f} | {r['cold_s']:.3f} | {r['warm_reparse_s']:.3f} | "
                f"{r['ratio']:.2f} | {r['ratio_vs_warm_reparse']:.2f} |"
            )
        out(
            f"\nmedian latency / cold: {sec['median_ratio']:.2f} (max {sec['max_ratio']:.2f}); "
            f"median latency / warm re-parse: {sec['median_ratio_vs_warm_reparse']:.2f}\n"
        )
    if "startup" in results:
        sec = results["startup"]
        out(f"## (d) start-up (subprocess, median of {sec['runs']} runs)\n")
        out("| case | median s | min s | max s | target s | result |")
        out("|---|---:|---:|---:|---:|---|")
        for r in sec["rows"]:
            out(
                f"| {r['case']} | {r['median_s']:.3f} | {r['min_s']:.3f} | {r['max_s']:.3f} | "
                f"{r['target_s']} | {verdict(r['median_s'] <= r['target_s'])} |"
            )
        out("")
    if "scaling" in results:
        sec = results["scaling"]
        out("## (e) scaling (generated chain problems)\n")
        out(
            "| objects | plan length | plan s | compile s | execute s | replan s | cold re-plan s |"
        )
        out("|---:|---:|---:|---:|---:|---:|---:|")
        for r in sec["rows"]:
            out(
                f"| {r['objects']} | {r['plan_length']} | {r['plan_s']:.3f} | "
                f"{r['compile_s']:.4f} | {r['execute_s']:.4f} | {r['replan_s']:.3f} | "
                f"{r['cold_replan_s']:.3f} |"
            )
        out(f"\nplot: {results.get('plot', 'not written')}\n")
    if "recovery" in results:
        print_section(results["recovery"], out)
    out("## targets\n")
    out("| target | measured | result |")
    out("|---|---:|---|")
    for label, measured, ok in results["targets"]:
        out(f"| {label} | {measured} | **{verdict(ok)}** |")


def targets_of(results: dict[str, Any]) -> list[tuple[str, str, bool]]:
    rows = []
    if "overhead" in results:
        value = results["overhead"]["median_overhead_pct"]
        rows.append(("median overhead <= 10% of planning time", f"{value:+.1f}%", value <= 10.0))
    if "thousand" in results:
        value = results["thousand"]["total_s"]
        rows.append(("1000-action plan compile + execute < 0.5 s", f"{value:.3f} s", value < 0.5))
    if "replan" in results:
        value = results["replan"]["median_ratio"]
        rows.append(("replan latency / cold re-plan <= 0.3 (median)", f"{value:.2f}", value <= 0.3))
    if "startup" in results:
        for r in results["startup"]["rows"]:
            rows.append(
                (
                    f"`{r['case']}` < {r['target_s']} s",
                    f"{r['median_s']:.3f} s",
                    r["median_s"] < r["target_s"],
                )
            )
    if "recovery" in results:
        for r in results["recovery"]["rows"]:
            if r["problem"] == RECOVERY_TARGET_PROBLEM and r["policy"] == "full, shared cache":
                value = r["median_share"]
                rows.append(
                    (
                        "planning <= 30% of the mission time, blocks-14 with faults "
                        "(median mission, shared plan cache)",
                        f"{value:.0%}",
                        value <= 0.3,
                    )
                )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few problems, one trial")
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    parser.add_argument("--trials", type=int, default=None, help="trials per problem")
    parser.add_argument(
        "--sections", default="abcdef", help="which sections to run (letters a-f, default all)"
    )
    parser.add_argument("--no-plot", action="store_true", help="do not write the PNG")
    args = parser.parse_args(argv)
    trials = args.trials or (1 if args.quick else 3)

    from plan_bridge.pddl.up_runtime import ensure_unified_planning
    from plan_bridge.planning.planner import get_planner

    started = time.perf_counter()
    ensure_unified_planning()
    planner = get_planner("fast-downward")
    planner.warm_up()
    results: dict[str, Any] = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "platform": platform.platform(),
            "load_before": " ".join(f"{x:.2f}" for x in os.getloadavg()),
        },
        "trials": trials,
        "quick": args.quick,
    }
    pairs, skipped = bench_problems(args.quick)
    results["skipped"] = skipped
    progress(f"{len(pairs)} parseable problems; not parsed by UP: {', '.join(skipped) or 'none'}")
    # Warm the worker (UP import, engine plug-ins) and this process's UP.
    from plan_bridge.pddl.task import load_task

    warm = load_task(BENCH / "gripper" / "domain.pddl", BENCH / "gripper" / "prob01.pddl")
    planner.solve(warm, timeout=60)
    direct_solve(BENCH / "gripper" / "domain.pddl", BENCH / "gripper" / "prob01.pddl")

    sections: dict[str, Callable[[], Any]] = {
        "a": lambda: ("overhead", overhead_section(pairs, trials, planner)),
        "b": lambda: ("thousand", thousand_section(5 if args.quick else 11)),
        "c": lambda: ("replan", replan_section(pairs, max(1, trials // 2), planner)),
        "d": lambda: ("startup", startup_section(3 if args.quick else 7)),
        "e": lambda: (
            "scaling",
            scaling_section([10, 40] if args.quick else [10, 25, 50, 100, 200, 400, 800], planner),
        ),
        "f": lambda: (
            "recovery",
            recovery_section(planner, 3 if args.quick else 10, quick=args.quick),
        ),
    }
    for letter in args.sections:
        progress(f"section ({letter})")
        key, value = sections[letter]()
        results[key] = value
        if args.json:  # keep what is done if a later section fails
            with open(args.json, "w", encoding="utf-8") as fh:
                json.dump(results, fh, indent=2, default=str)
    if "scaling" in results and not args.no_plot and plot_scaling(results["scaling"]["rows"], PNG):
        results["plot"] = str(PNG.relative_to(ROOT))
    results["machine"]["load_after"] = " ".join(f"{x:.2f}" for x in os.getloadavg())
    results["targets"] = targets_of(results)
    results["elapsed_s"] = time.perf_counter() - started
    print_report(results)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=2, default=str)
        progress(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
