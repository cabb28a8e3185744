"""The study's report: success rates with intervals, authoring cost, plots, report.md."""

from __future__ import annotations

import csv
import math
import sys
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from plan_bridge.study.runs import APPROACHES, target_of

__all__ = ["authoring_cost", "summarise_results", "wilson", "write_report"]


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
    from plan_bridge.planning.planner import PlanStep

    target = target_of(target_path, problem)
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
