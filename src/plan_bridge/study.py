"""The scripted-vs-planned study: run missions under approaches, fault rates and seeds.

``plan-bridge study TARGET... --runs N --fault-rates 0,0.1,0.2,0.4 --out DIR`` runs
every (target, approach, fault rate, seed) in worker processes, appends one row per
finished run to ``DIR/results.csv`` (flushed and synced: a killed study continues
where it stopped, and a run is never counted twice), then writes ``summary.csv``,
``authoring.csv``, PNG plots and ``report.md``.

Approaches: ``scripted`` (the domain's hand-written baseline), ``planned`` (the
executive with the full recovery policy), the ablations ``no-replan``,
``retry-only`` and ``replan-only``, and ``pyperplan`` (full policy, other planner).
"""

from __future__ import annotations

import argparse
import csv
import math
import multiprocessing
import os
import queue
import sys
import time
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plan_bridge.cli import EXIT_BAD_INPUT, EXIT_OK, Command, fail, register

__all__ = ["APPROACHES", "RunSpec", "run_one", "run_study", "summarise_results"]

APPROACHES: dict[str, tuple[str, str]] = {
    # name: (policy, planner); "scripted" has no planner.
    "scripted": ("", ""),
    "planned": ("full", "fast-downward"),
    "no-replan": ("no-replan", "fast-downward"),
    "retry-only": ("retry-only", "fast-downward"),
    "replan-only": ("replan-only", "fast-downward"),
    "pyperplan": ("full", "pyperplan"),
}
DEFAULT_APPROACHES = ("scripted", "planned", "no-replan", "retry-only", "replan-only")

FIELDS = [
    "target",
    "problem",
    "variant",
    "approach",
    "fault_rate",
    "seed",
    "outcome",
    "goal_reached",
    "wall_time_s",
    "sim_time_s",
    "steps",
    "actions_executed",
    "actions_failed",
    "faults_injected",
    "retries",
    "continues",
    "repairs",
    "replans",
    "planner_calls",
    "planning_time_s",
    "absorbed_skill",
    "absorbed_retry",
    "absorbed_continue",
    "absorbed_repair",
    "absorbed_replan",
    "error",
]


@dataclass(frozen=True)
class RunSpec:
    """One run of the study."""

    target: str
    approach: str
    fault_rate: float
    seed: int
    problem: str = ""
    variant: str = ""

    @property
    def key(self) -> tuple[str, str, str, str, str, str]:
        return (
            Path(self.target).name,
            self.problem,
            self.variant,
            self.approach,
            f"{self.fault_rate:g}",
            str(self.seed),
        )


def _row_key(row: dict[str, str]) -> tuple[str, str, str, str, str, str]:
    return (
        row["target"],
        row["problem"],
        row["variant"],
        row["approach"],
        f"{float(row['fault_rate']):g}",
        row["seed"],
    )


# -- one run (in a worker process) ---------------------------------------------------------
_targets: dict[tuple[str, str], Any] = {}


def _target(path: str, problem: str) -> Any:
    from plan_bridge.mission import load_target
    from plan_bridge.worker import default_pool

    key = (path, problem)
    if key not in _targets:
        _targets[key] = load_target(path, problem or None, prime=default_pool())
    return _targets[key]


def _call_domain(fn: Any, task: Any, spec: RunSpec) -> Any:
    import inspect

    kwargs: dict[str, Any] = {"seed": spec.seed, "fail_rate": spec.fault_rate}
    if spec.variant:
        if "variant" not in inspect.signature(fn).parameters:
            raise ValueError(f"{spec.target}: {fn.__name__}() does not support variants")
        kwargs["variant"] = spec.variant
    return fn(task, **kwargs)


def run_one(spec: RunSpec) -> dict[str, Any]:
    """Run one mission and measure it; never raises (errors become rows)."""
    row: dict[str, Any] = dict.fromkeys(FIELDS, "")
    key = spec.key
    row.update(
        target=key[0],
        problem=key[1],
        variant=key[2],
        approach=key[3],
        fault_rate=key[4],
        seed=key[5],
    )
    clock: list[float] = []
    try:
        row.update(_run(spec, clock))
    except Exception as exc:
        row.update(outcome="error", goal_reached=False, error=f"{type(exc).__name__}: {exc}"[:300])
    # Wall time of the mission itself: loading the target is shared by all runs.
    row["wall_time_s"] = round(time.monotonic() - clock[0], 4) if clock else 0.0
    return row


def _count_steps(events: list[Any]) -> int:
    return sum(1 for e in events if e.kind == "state_exited")


def _run(spec: RunSpec, clock: list[float]) -> dict[str, Any]:
    from plan_bridge.executive import Executive, ReplanPolicy
    from plan_bridge.planning import get_planner

    target = _target(spec.target, spec.problem)
    task = target.task
    clock.append(time.monotonic())
    exits: list[Any] = []

    def count(event: Any) -> None:
        if event.kind == "state_exited":
            exits.append(event)

    if spec.approach == "scripted":
        scripted = getattr(target.module, "scripted", None)
        if scripted is None:
            raise ValueError(f"{target.name} has no scripted baseline")
        mission = _call_domain(scripted, task, spec)
        machine = mission.machine
        if hasattr(machine, "add_listener"):
            machine.add_listener(count)
        outcome = machine.execute()
        world = mission.world
        faults = getattr(world, "faults_injected", 0)
        reached = bool(world.goal_reached())
        return {
            "outcome": outcome,
            "goal_reached": reached,
            "sim_time_s": round(getattr(world, "sim_time", 0.0), 3),
            "steps": _count_steps(exits),
            "actions_executed": getattr(world, "actions_run", ""),
            "faults_injected": faults,
        }
    policy_name, planner_name = APPROACHES[spec.approach]
    if target.module is not None and hasattr(target.module, "setup"):
        setup = _call_domain(target.module.setup, task, spec)
    else:
        setup = target.setup(seed=spec.seed, fail_rate=spec.fault_rate)
    executive = Executive(
        task,
        setup.skills,
        get_planner(planner_name),
        policy=ReplanPolicy.named(policy_name),
        sense=setup.sense,
        concurrent=setup.concurrent,
    )
    executive.add_listener(count)
    outcome = executive.execute()
    report = executive.report
    world = setup.world
    faults = getattr(world, "faults_injected", 0)
    decisions = [d["decision"] for d in report.decisions]
    failed = report.actions_failed
    return {
        "outcome": outcome,
        "goal_reached": bool(world.goal_reached()) if world is not None else report.goal_reached,
        "sim_time_s": round(getattr(world, "sim_time", 0.0), 3),
        "steps": _count_steps(exits),
        "actions_executed": report.actions_executed,
        "actions_failed": failed,
        "faults_injected": faults,
        "retries": report.retries,
        "continues": report.continues,
        "repairs": report.repairs,
        "replans": report.replans,
        "planner_calls": report.planner_calls,
        "planning_time_s": round(report.planning_time_s, 4),
        # Faults that never surfaced as a failed step were absorbed inside the skills
        # (local retries, re-detections); the others by the executive's decisions.
        "absorbed_skill": max(0, faults - failed),
        "absorbed_retry": decisions.count("retry"),
        "absorbed_continue": decisions.count("continue"),
        "absorbed_repair": decisions.count("repair"),
        "absorbed_replan": decisions.count("replan"),
    }


# -- the worker pool ----------------------------------------------------------------------------
def _worker(tasks: Any, results: Any) -> None:
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    from plan_bridge.planning import get_planner

    # Start the planner's worker process now, so the first run is not charged for it.
    get_planner("fast-downward").warm_up()
    while True:
        item = tasks.get()
        if item is None:
            return
        index, spec = item
        results.put((index, run_one(spec)))


@dataclass
class _Worker:
    process: Any
    tasks: Any
    current: tuple[int, RunSpec] | None = None
    since: float = 0.0


class _Pool:
    """Worker processes with a per-run time limit: a stuck run is killed, not waited for."""

    def __init__(self, jobs: int) -> None:
        self.ctx = multiprocessing.get_context("spawn")
        self.results: Any = self.ctx.Queue()
        self.workers = [self._start() for _ in range(jobs)]

    def _start(self) -> _Worker:
        tasks = self.ctx.Queue()
        process = self.ctx.Process(target=_worker, args=(tasks, self.results), daemon=True)
        process.start()
        return _Worker(process, tasks)

    def run(self, specs: list[RunSpec], run_timeout: float, on_result: Any) -> None:
        pending = list(enumerate(specs))[::-1]
        while pending or any(w.current is not None for w in self.workers):
            for worker in self.workers:
                if worker.current is None and pending:
                    worker.current = pending.pop()
                    worker.since = time.monotonic()
                    worker.tasks.put(worker.current)
            try:
                index, row = self.results.get(timeout=0.5)
            except queue.Empty:
                pass
            else:
                for worker in self.workers:
                    if worker.current is not None and worker.current[0] == index:
                        worker.current = None
                on_result(specs[index], row)
            self._reap(run_timeout, on_result)

    def _reap(self, run_timeout: float, on_result: Any) -> None:
        """Replace workers that died or overran their run, recording that run."""
        now = time.monotonic()
        for n, worker in enumerate(self.workers):
            if worker.current is None:
                continue
            overran = now - worker.since > run_timeout
            if worker.process.is_alive() and not overran:
                continue
            worker.process.kill()
            worker.process.join(5)
            spec = worker.current[1]
            row: dict[str, Any] = dict.fromkeys(FIELDS, "")
            row.update(
                zip(
                    ("target", "problem", "variant", "approach", "fault_rate", "seed"),
                    spec.key,
                    strict=True,
                )
            )
            row.update(
                outcome="timeout" if overran else "crashed",
                goal_reached=False,
                wall_time_s=round(now - worker.since, 3),
                error=f"run exceeded {run_timeout:g} s"
                if overran
                else f"worker died (exit {worker.process.exitcode})",
            )
            self.workers[n] = self._start()
            on_result(spec, row)

    def close(self) -> None:
        for worker in self.workers:
            worker.tasks.put(None)
        for worker in self.workers:
            worker.process.join(5)
            if worker.process.is_alive():
                worker.process.kill()


# -- the study ------------------------------------------------------------------------------------
def read_results(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with path.open(newline="", encoding="utf-8") as f:
        return [row for row in csv.DictReader(f) if row.get("outcome")]


def run_study(
    specs: Sequence[RunSpec],
    out: Path,
    *,
    jobs: int = 2,
    run_timeout: float = 300.0,
    progress: Any = None,
) -> list[dict[str, str]]:
    """Run what ``results.csv`` in ``out`` does not have yet; return every requested row."""
    from smach.introspection.journal import drop_torn_line

    out.mkdir(parents=True, exist_ok=True)
    results_path = out / "results.csv"
    drop_torn_line(results_path)
    existing = read_results(results_path)
    done = {_row_key(r) for r in existing}
    todo = [s for s in specs if s.key not in done]
    new_file = not results_path.exists() or results_path.stat().st_size == 0
    started = time.monotonic()
    finished = 0
    with results_path.open("a", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        if new_file:
            writer.writeheader()

        def on_result(spec: RunSpec, row: dict[str, Any]) -> None:
            nonlocal finished
            writer.writerow(row)
            f.flush()
            os.fsync(f.fileno())
            finished += 1
            if progress is not None:
                progress(finished, len(todo), spec, row, time.monotonic() - started)

        if todo:
            pool = _Pool(max(1, min(jobs, len(todo))))
            try:
                pool.run(todo, run_timeout, on_result)
            finally:
                pool.close()
    wanted = {s.key for s in specs}
    rows = [r for r in read_results(results_path) if _row_key(r) in wanted]
    # A resumed study may hold a row twice if a crash hit between write and fsync: keep one.
    unique: dict[tuple[str, ...], dict[str, str]] = {}
    for row in rows:
        unique.setdefault(_row_key(row), row)
    return list(unique.values())


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95% Wilson score interval of a proportion."""
    if n == 0:
        return (0.0, 0.0)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def _f(value: str) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return 0.0


def summarise_results(rows: Iterable[dict[str, str]]) -> list[dict[str, Any]]:
    groups: dict[tuple[str, str, str, float], list[dict[str, str]]] = defaultdict(list)
    for row in rows:
        groups[(row["target"], row["variant"], row["approach"], _f(row["fault_rate"]))].append(row)
    summary = []
    for (target, variant, approach, rate), items in sorted(groups.items()):
        ok = [r for r in items if r["goal_reached"] == "True"]
        low, high = wilson(len(ok), len(items))
        wall = sum(_f(r["wall_time_s"]) for r in ok) / len(ok) if ok else 0.0
        planning = sum(_f(r["planning_time_s"]) for r in items)
        total = sum(_f(r["wall_time_s"]) for r in items)
        summary.append(
            {
                "target": target,
                "variant": variant,
                "approach": approach,
                "fault_rate": rate,
                "runs": len(items),
                "success_rate": round(len(ok) / len(items), 4),
                "ci_low": round(low, 4),
                "ci_high": round(high, 4),
                "errors": sum(1 for r in items if r["outcome"] in ("error", "timeout", "crashed")),
                "mean_wall_time_s": round(wall, 4),
                "mean_sim_time_s": round(sum(_f(r["sim_time_s"]) for r in ok) / len(ok), 3)
                if ok
                else 0.0,
                "mean_steps": round(sum(_f(r["steps"]) for r in ok) / len(ok), 2) if ok else 0.0,
                "mean_actions": round(sum(_f(r["actions_executed"]) for r in ok) / len(ok), 2)
                if ok
                else 0.0,
                "mean_faults": round(sum(_f(r["faults_injected"]) for r in items) / len(items), 2),
                "planning_share": round(planning / total, 4) if total else 0.0,
                "mean_replans": round(sum(_f(r["replans"]) for r in items) / len(items), 2),
                **{
                    f"absorbed_{layer}": round(
                        sum(_f(r[f"absorbed_{layer}"]) for r in items) / len(items), 3
                    )
                    for layer in ("skill", "retry", "continue", "repair", "replan")
                },
            }
        )
    return summary


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    if not rows:
        path.write_text("")
        return
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


# -- authoring cost --------------------------------------------------------------------------------
def _code_lines(path: Path) -> int:
    """Non-blank lines that are not comments or docstring-only lines (a rough LOC)."""
    if not path.exists():
        return 0
    count = 0
    in_doc = False
    for raw in path.read_text(encoding="utf-8").splitlines():
        line = raw.strip()
        if not line or line.startswith("#") or line.startswith(";"):
            continue
        quotes = line.count('"""') + line.count("'''")
        if in_doc:
            if quotes % 2 == 1:
                in_doc = False
            continue
        if line.startswith(('"""', "'''")):
            if quotes == 1:
                in_doc = True
            continue
        count += 1
    return count


def _structure_size(state: Any) -> tuple[int, int]:
    from smach.introspection.structure import snapshot

    node = snapshot(state)
    states = sum(1 for n in node.walk() if not n.is_container)
    edges = sum(len(n.edges) for n in node.walk())
    return states, edges


def authoring_cost(target_path: str, problem: str = "") -> list[dict[str, Any]]:
    """Lines of code, states and transitions, and PDDL size per approach of a target."""
    from plan_bridge.planning import PlanStep

    target = _target(target_path, problem)
    folder = target.folder or Path(target_path).parent
    task = target.task
    rows: list[dict[str, Any]] = []
    pddl_lines = _code_lines(target.domain_path)
    if target.module is not None and hasattr(target.module, "scripted"):
        mission = target.module.scripted(task, seed=0, fail_rate=0.0)
        states, edges = _structure_size(mission.machine)
        rows.append(
            {
                "target": target.name,
                "approach": "scripted",
                "python_lines": _code_lines(folder / "scripted.py"),
                "pddl_lines": 0,
                "pddl_actions": 0,
                "pddl_predicates": 0,
                "states": states,
                "transitions": edges,
            }
        )
    states = edges = 0
    if target.module is not None and hasattr(target.module, "setup"):
        setup = target.module.setup(task, seed=0, fail_rate=0.0)
        for name, schema in task.actions.items():
            example = []
            for parameter in schema.parameters:
                candidates = task.objects_of_type(parameter.type)
                example.append(candidates[0] if candidates else parameter.name)
            state, _ = setup.skills.create(PlanStep(name, tuple(example)))
            s, e = _structure_size(state)
            states += s
            edges += e
    rows.append(
        {
            "target": target.name,
            "approach": "planned",
            "python_lines": _code_lines(folder / "skills.py"),
            "pddl_lines": pddl_lines,
            "pddl_actions": len(task.actions),
            "pddl_predicates": len(task.predicates),
            "states": states,
            "transitions": edges,
        }
    )
    return rows


# -- plots and report -------------------------------------------------------------------------------
def _plots(summary: list[dict[str, Any]], out: Path) -> list[str]:
    try:
        import matplotlib
    except ImportError:
        print(
            "plan-bridge study: matplotlib is not installed, so no plots "
            "(pip install 'smach-planner[study]')",
            file=sys.stderr,
        )
        return []

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files: list[str] = []
    targets = sorted({(s["target"], s["variant"]) for s in summary})
    approaches = sorted(
        {s["approach"] for s in summary},
        key=lambda a: list(APPROACHES).index(a) if a in APPROACHES else 99,
    )
    if not targets:
        return files

    def panel_title(target: str, variant: str) -> str:
        return f"{target} ({variant})" if variant else target

    fig, axes = plt.subplots(1, len(targets), figsize=(4.6 * len(targets), 3.8), squeeze=False)
    for ax, (target, variant) in zip(axes[0], targets, strict=True):
        for approach in approaches:
            pts = sorted(
                (s["fault_rate"], s["success_rate"], s["ci_low"], s["ci_high"])
                for s in summary
                if s["target"] == target and s["variant"] == variant and s["approach"] == approach
            )
            if not pts:
                continue
            xs = [p[0] for p in pts]
            ys = [p[1] * 100 for p in pts]
            err = [[(p[1] - p[2]) * 100 for p in pts], [(p[3] - p[1]) * 100 for p in pts]]
            ax.errorbar(xs, ys, yerr=err, marker="o", capsize=3, label=approach)
        ax.set_title(panel_title(target, variant))
        ax.set_xlabel("fault rate")
        ax.set_ylabel("goal reached (%)")
        ax.set_ylim(-5, 105)
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="lower left")
    fig.suptitle("Success rate vs fault rate (95% Wilson intervals)")
    fig.tight_layout()
    fig.savefig(out / "success_vs_fault_rate.png", dpi=110)
    plt.close(fig)
    files.append("success_vs_fault_rate.png")

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    labels = [f"{panel_title(t, v)}\n{a}" for (t, v) in targets for a in approaches]
    for ax, key, ylabel in (
        (axes[0], "mean_sim_time_s", "simulated robot time per successful run (s)"),
        (axes[1], "mean_steps", "states executed per successful run"),
    ):
        values = []
        for t, v in targets:
            for a in approaches:
                rows = [
                    s
                    for s in summary
                    if s["target"] == t and s["variant"] == v and s["approach"] == a
                ]
                values.append(sum(s[key] for s in rows) / len(rows) if rows else 0)
        ax.bar(
            range(len(values)),
            values,
            color=[f"C{i % len(approaches)}" for i in range(len(values))],
        )
        ax.set_xticks(range(len(values)))
        ax.set_xticklabels(labels, rotation=70, fontsize=7)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.grid(axis="y", alpha=0.3)
    fig.suptitle("Cost of successful runs (averaged over fault rates)")
    fig.tight_layout()
    fig.savefig(out / "time_and_actions.png", dpi=110)
    plt.close(fig)
    files.append("time_and_actions.png")

    planned = [a for a in approaches if a != "scripted"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    ax = axes[0]
    for approach in planned:
        shares = sorted(
            (s["fault_rate"], s["planning_share"] * 100)
            for s in summary
            if s["approach"] == approach
        )
        by_rate: dict[float, list[float]] = defaultdict(list)
        for rate, share in shares:
            by_rate[rate].append(share)
        xs = sorted(by_rate)
        ax.plot(xs, [sum(by_rate[x]) / len(by_rate[x]) for x in xs], marker="o", label=approach)
    ax.set_xlabel("fault rate")
    ax.set_ylabel("planning time / wall time (%)")
    ax.set_title("Planning share of time")
    ax.grid(alpha=0.3)
    if planned:
        ax.legend(fontsize=8)
    ax = axes[1]
    layers = ("skill", "retry", "continue", "repair", "replan")
    bottoms = [0.0] * len(planned)
    for layer in layers:
        vals = []
        for approach in planned:
            rows = [s for s in summary if s["approach"] == approach]
            vals.append(sum(s[f"absorbed_{layer}"] for s in rows) / len(rows) if rows else 0)
        ax.bar(planned, vals, bottom=bottoms, label=layer)
        bottoms = [b + v for b, v in zip(bottoms, vals, strict=True)]
    ax.set_ylabel("faults absorbed per run")
    ax.set_title("Where faults were absorbed")
    ax.legend(fontsize=8)
    ax.tick_params(axis="x", labelsize=8)
    fig.tight_layout()
    fig.savefig(out / "planning_share_and_absorption.png", dpi=110)
    plt.close(fig)
    files.append("planning_share_and_absorption.png")
    return files


def write_report(
    rows: list[dict[str, str]], out: Path, authoring: list[dict[str, Any]], command: str
) -> Path:
    summary = summarise_results(rows)
    _write_csv(out / "summary.csv", summary)
    _write_csv(out / "authoring.csv", authoring)
    plots = _plots(summary, out)
    lines = [
        "# Scripted vs planned: study report",
        "",
        f"Command: `{command}`",
        "",
        f"{len(rows)} runs. Success = the goal holds in the simulated world at the end. "
        "Intervals are 95% Wilson score intervals.",
        "",
        "## Findings",
        "",
    ]
    lines += _findings(summary, authoring)
    lines += [
        "",
        "## Success rate by fault rate",
        "",
        "| target | approach | fault rate | runs | goal reached | 95% CI | mean wall time (s) | mean sim time (s) | planning share | replans/run |",
        "|---|---|---:|---:|---:|---|---:|---:|---:|---:|",
    ]
    for s in summary:
        name = f"{s['target']} ({s['variant']})" if s["variant"] else s["target"]
        lines.append(
            f"| {name} | {s['approach']} | {s['fault_rate']:g} | {s['runs']} | "
            f"{s['success_rate'] * 100:.0f}% | {s['ci_low'] * 100:.0f}-{s['ci_high'] * 100:.0f}% | "
            f"{s['mean_wall_time_s']:.3f} | {s['mean_sim_time_s']:.1f} | {s['planning_share'] * 100:.0f}% | "
            f"{s['mean_replans']:.2f} |"
        )
    lines += [
        "",
        "## Authoring cost",
        "",
        "| target | approach | Python lines | PDDL lines | PDDL actions | states | transitions |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for a in authoring:
        lines.append(
            f"| {a['target']} | {a['approach']} | {a['python_lines']} | {a['pddl_lines']} | "
            f"{a['pddl_actions']} | {a['states']} | {a['transitions']} |"
        )
    lines += ["", "## Plots", ""]
    lines += [f"![{p}]({p})" for p in plots]
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _findings(summary: list[dict[str, Any]], authoring: list[dict[str, Any]]) -> list[str]:
    out: list[str] = []
    by = {(s["target"], s["variant"], s["approach"], s["fault_rate"]): s for s in summary}
    targets = sorted({(s["target"], s["variant"]) for s in summary})
    for target, variant in targets:
        rates = sorted(
            {s["fault_rate"] for s in summary if s["target"] == target and s["variant"] == variant}
        )
        if not rates:
            continue
        top = rates[-1]
        name = f"{target} ({variant})" if variant else target
        parts = []
        for approach in APPROACHES:
            s = by.get((target, variant, approach, top))
            if s:
                parts.append(
                    f"{approach} {s['success_rate'] * 100:.0f}% ({s['ci_low'] * 100:.0f}-{s['ci_high'] * 100:.0f}%)"
                )
        out.append(f"- **{name}**, fault rate {top:g}: goal reached by " + ", ".join(parts) + ".")
        planned = by.get((target, variant, "planned", top))
        scripted = by.get((target, variant, "scripted", top))
        if planned and scripted and scripted["mean_wall_time_s"] and planned["mean_wall_time_s"]:
            out.append(
                f"  Successful planned runs took {planned['mean_wall_time_s']:.2f} s of wall time "
                f"({planned['planning_share'] * 100:.0f}% planning) vs {scripted['mean_wall_time_s']:.3f} s scripted."
            )
    costs: dict[str, dict[str, dict[str, Any]]] = defaultdict(dict)
    for a in authoring:
        costs[a["target"]][a["approach"]] = a
    for target, c in sorted(costs.items()):
        if "scripted" in c and "planned" in c:
            out.append(
                f"- Authoring {target}: scripted {c['scripted']['python_lines']} Python lines, "
                f"{c['scripted']['states']} states, {c['scripted']['transitions']} transitions; planned "
                f"{c['planned']['python_lines']} Python lines of skills + {c['planned']['pddl_lines']} PDDL lines "
                f"({c['planned']['pddl_actions']} actions)."
            )
    return out


# -- CLI ------------------------------------------------------------------------------------------
def _float_list(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}"
        ) from None
    if not values or any(not 0 <= v <= 1 for v in values):
        raise argparse.ArgumentTypeError(f"fault rates must be between 0 and 1: {text!r}")
    return values


def _configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "targets", nargs="+", metavar="TARGET", help="domain folders (domains/NAME)"
    )
    parser.add_argument("--runs", type=int, default=10, help="seeds per configuration (default 10)")
    parser.add_argument("--seeds", help="explicit comma-separated seeds (overrides --runs)")
    parser.add_argument("--fault-rates", type=_float_list, default=[0.0, 0.1, 0.2, 0.4])
    parser.add_argument(
        "--approaches",
        default=",".join(DEFAULT_APPROACHES),
        help=f"comma-separated: {', '.join(APPROACHES)}",
    )
    parser.add_argument(
        "--problem", default="", help="problem name in each folder's problems/ (default: the first)"
    )
    parser.add_argument(
        "--variant", default="", help="a world variant the domains support, e.g. 'unanticipated'"
    )
    parser.add_argument(
        "--out", default="study-results", help="output folder (default study-results)"
    )
    parser.add_argument(
        "--jobs", type=int, default=max(1, min(2, os.cpu_count() or 1)), help="worker processes"
    )
    parser.add_argument(
        "--run-timeout", type=float, default=300.0, help="seconds before a stuck run is killed"
    )


def _run_command(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.mission import load_target

    approaches = [a.strip() for a in args.approaches.split(",") if a.strip()]
    unknown = [a for a in approaches if a not in APPROACHES]
    if unknown:
        return fail(f"unknown approaches {unknown}; approaches: {', '.join(APPROACHES)}")
    if args.runs < 1 or args.jobs < 1:
        return fail("--runs and --jobs must be at least 1")
    try:
        seeds = [int(s) for s in args.seeds.split(",")] if args.seeds else list(range(args.runs))
    except ValueError:
        return fail(f"--seeds must be comma-separated integers, got {args.seeds!r}")
    try:
        for target in args.targets:
            loaded = load_target(target, args.problem or None)
            if "scripted" in approaches and not hasattr(loaded.module, "scripted"):
                return fail(
                    f"{target}: no scripted baseline (scripted() in the domain's Python); drop 'scripted' from --approaches"
                )
    except PlanBridgeError as exc:
        return fail(str(exc))
    specs = [
        RunSpec(str(t), a, r, s, args.problem, args.variant)
        for t in args.targets
        for a in approaches
        for r in args.fault_rates
        for s in seeds
    ]
    out = Path(args.out)

    def progress(done: int, total: int, spec: RunSpec, row: dict[str, Any], elapsed: float) -> None:
        width = 24
        filled = int(width * done / total)
        eta = elapsed / done * (total - done)
        print(
            f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} "
            f"{Path(spec.target).name} {spec.approach} p={spec.fault_rate:g} seed {spec.seed}: "
            f"{row['outcome']} ETA {eta:4.0f} s   ",
            end="" if done < total else "\n",
            file=sys.stderr,
            flush=True,
        )

    total_runs = len(specs)
    print(
        f"plan-bridge study: {total_runs} runs ({len(args.targets)} targets x {len(approaches)} approaches x {len(args.fault_rates)} fault rates x {len(seeds)} seeds), {args.jobs} workers, results in {out}/",
        file=sys.stderr,
        flush=True,
    )
    rows = run_study(specs, out, jobs=args.jobs, run_timeout=args.run_timeout, progress=progress)
    authoring: list[dict[str, Any]] = []
    for target in args.targets:
        authoring += authoring_cost(str(target), args.problem)
    command = "plan-bridge study " + " ".join(sys.argv[2:] if len(sys.argv) > 2 else args.targets)
    report = write_report(rows, out, authoring, command)
    errors = sum(1 for r in rows if r["outcome"] in ("error", "timeout", "crashed"))
    print(f"{len(rows)} runs ({errors} errors); report: {report}", file=sys.stderr)
    return EXIT_OK if errors == 0 else 1


register(
    Command("study", "compare scripted and planned missions under faults", _configure, _run_command)
)
assert EXIT_BAD_INPUT == 2
