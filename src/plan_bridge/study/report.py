"""The study's report: setup, success rates with intervals, comparisons with p-values,
authoring cost, plots with captions, ``report.md``.

Means and medians of times and steps are over *successful* runs only (a failed run
stops early), and say so; cells with no successful run show "n/a", never 0. The
mean wall time over all runs is given too, so nothing depends on that selection.
This module is over 400 lines because the report's text is long; the numbers come
from :mod:`~plan_bridge.study.comparison` and the plots from
:mod:`~plan_bridge.study.figures`.
"""

from __future__ import annotations

import csv
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from plan_bridge.study.cells import NA, cell_columns, errors
from plan_bridge.study.comparison import compare_approaches, format_p
from plan_bridge.study.environment import PLANNER_PACKAGES, read_sessions
from plan_bridge.study.figures import draw_figures
from plan_bridge.study.order_streams import order_section, summarise_orders
from plan_bridge.study.runs import (
    APPROACHES,
    TEMPORAL_TIME_SCALE,
    cell_label,
    cell_number,
    target_of,
)
from plan_bridge.study.statistics import median_ci, wilson

__all__ = ["authoring_cost", "fault_model", "summarise_results", "wilson", "write_report"]


def summarise_results(rows: Iterable[dict[str, str]]) -> list[dict[str, Any]]:
    groups: dict[tuple[str, str, str, str, float], list[dict[str, str]]] = defaultdict(list)
    for row in rows:
        cell = (row["target"], row["variant"], row.get("orders") or "")
        groups[(*cell, row["approach"], cell_number(row["fault_rate"]))].append(row)
    summary = []
    for (target, variant, orders, approach, rate), items in sorted(groups.items()):
        ok = [r for r in items if r["goal_reached"] == "True"]
        low, high = wilson(len(ok), len(items))
        planning = sum(cell_number(r["planning_time_s"]) for r in items)
        total = sum(cell_number(r["wall_time_s"]) for r in items)

        def mean_ok(column: str, digits: int, ok: list[dict[str, str]] = ok) -> float | str:
            return round(sum(cell_number(r[column]) for r in ok) / len(ok), digits) if ok else NA

        def mean_reported(column: str, ok: list[dict[str, str]] = ok) -> float | str:
            # A world that does not report the number: '' (not 0).
            values = [cell_number(r[column]) for r in ok if r.get(column)]
            return round(sum(values) / len(values), 3) if values else NA if not ok else ""

        wall: tuple[float | str, ...] = (
            tuple(round(v, 4) for v in median_ci([cell_number(r["wall_time_s"]) for r in ok]))
            if ok
            else (NA, NA, NA)
        )
        summary.append(
            {
                **cell_columns((target, variant, orders, rate), approach, items),
                "successes": len(ok),
                "success_rate": round(len(ok) / len(items), 4),
                "ci_low": round(low, 4),
                "ci_high": round(high, 4),
                "errors": errors(items),
                "median_wall_time_s": wall[0],
                "median_wall_ci_low": wall[1],
                "median_wall_ci_high": wall[2],
                "mean_wall_time_s": mean_ok("wall_time_s", 4),
                "mean_wall_time_all_s": round(total / len(items), 4),
                "mean_sim_time_s": mean_ok("sim_time_s", 3),
                "mean_distance_m": mean_reported("distance_m"),
                "mean_battery_used": mean_reported("battery_used"),
                "mean_steps": mean_ok("steps", 2),
                "mean_actions": mean_ok("actions_executed", 2),
                "mean_faults": round(
                    sum(cell_number(r["faults_injected"]) for r in items) / len(items), 2
                ),
                "planning_share": round(planning / total, 4) if total else 0.0,
                "mean_replans": round(
                    sum(cell_number(r["replans"]) for r in items) / len(items), 2
                ),
                "mean_planner_calls": round(
                    sum(cell_number(r.get("planner_calls", "")) for r in items) / len(items), 2
                ),
                "mean_repairs": round(
                    sum(cell_number(r.get("repairs", "")) for r in items) / len(items), 2
                ),
                **{
                    f"absorbed_{layer}": round(
                        sum(cell_number(r[f"absorbed_{layer}"]) for r in items) / len(items), 3
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
    from plan_bridge.planning.types import PlanStep

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


def fault_model(target_path: str, problem: str = "") -> dict[str, float]:
    """Fault name -> probability per unit of fault rate, from the domain's world."""
    from plan_bridge.execution.simulation import SimulatedWorld
    from plan_bridge.missions.world_target import WorldTarget

    target = target_of(target_path, problem)
    if isinstance(target, WorldTarget):
        return {"a robot action fails (pyrobosim's ExecutionOptions)": 1.0}
    if not target.has_own_skills:
        return {}
    world = target.setup(seed=0, fail_rate=0.0).world
    return dict(world.fault_scale) if isinstance(world, SimulatedWorld) else {}


# -- report.md ------------------------------------------------------------------------------------
def _num(value: Any, fmt: str) -> str:
    return NA if value == NA else format(value, fmt)


def _reported(value: Any, fmt: str) -> str:
    """A number only some worlds report: blank where this one does not."""
    return "" if value == "" else _num(value, fmt)


def _seconds(value: Any, fmt: str) -> str:
    return NA if value == NA else f"{format(value, fmt)} s"


def _ranges(values: list[int]) -> str:
    """0,1,2,3,7 -> '0-3, 7'."""
    spans: list[list[int]] = []
    for v in sorted(set(values)):
        if spans and spans[-1][1] == v - 1:
            spans[-1][1] = v
        else:
            spans.append([v, v])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in spans)


def _setup_section(
    rows: list[dict[str, str]],
    summary: list[dict[str, Any]],
    out: Path,
    fault_models: dict[str, dict[str, float]],
) -> list[str]:
    seeds = [int(r["seed"]) for r in rows if r["seed"].lstrip("-").isdigit()]
    rates = sorted({cell_number(r["fault_rate"]) for r in rows})
    per_cell = sorted({s["runs"] for s in summary})
    approaches = sorted({r["approach"] for r in rows}, key=lambda a: list(APPROACHES).index(a))
    lines = [
        "## Setup",
        "",
        f"- Runs: {len(rows)}; runs per cell (mission x approach x fault rate): "
        + (f"{per_cell[0]}" if len(per_cell) == 1 else f"{per_cell[0]}-{per_cell[-1]}")
        + f"; seeds {_ranges(seeds)} (one run per seed in every cell, the same seeds for "
        "every approach, so every approach meets the same worlds and faults).",
        f"- Fault rates: {', '.join(f'{r:g}' for r in rates)}. Approaches (policy, "
        "planner; for `auto` the engines that found the plans): "
        + "; ".join(
            f"`{a}` ({APPROACHES[a][0] or 'hand-written machine'}"
            + (f", {_planner_text(a, rows)}" if APPROACHES[a][1] else "")
            + ")"
            for a in approaches
        )
        + ".",
    ]
    fault_models = {t: m for t, m in fault_models.items() if m}
    if fault_models:
        lines += [
            "- Fault model: each fault is drawn from the run's seeded generator with "
            "probability *scale x fault rate* (capped at 1) at the moment the domain's "
            "world (its `world.py`; for timed worlds `plan_bridge.execution.timed_world`) "
            "says:",
            "",
            "  | mission | fault | scale |",
            "  |---|---|---:|",
        ]
        for target, model in sorted(fault_models.items()):
            lines += [f"  | {target} | {name} | {scale:g} |" for name, scale in model.items()]
        lines.append("")
    sessions = read_sessions(out)
    packages: dict[str, str] = {}
    machines: dict[tuple[str, str, int], set[str]] = defaultdict(set)
    for session in sessions:
        writer = session.get("writer", {})
        packages.update(writer.get("packages", {}))
        for worker in session.get("workers", {}).values():
            key = (
                worker.get("host", "?"),
                worker.get("cpu_model", "?"),
                worker.get("cpu_count", 0),
            )
            machines[key].add(f"Python {worker.get('python', '?')}, {worker.get('platform', '?')}")
    if sessions:
        lines.append(
            "- Executed by: "
            + "; ".join(
                f"{s.get('executor', '?')} ({s.get('started', '?')}"
                + (f", source {s['source']}" if s.get("source") else "")
                + ")"
                for s in sessions
            )
            + ". A source marked +dirty had uncommitted edits in src/ or domains/."
        )
    for (host, cpu, count), systems in sorted(machines.items()):
        lines.append(f"- Machine `{host}`: {cpu}, {count} CPUs; {'; '.join(sorted(systems))}.")
    lines += _placement_lines(rows)
    if packages:
        lines.append(
            "- Packages: " + ", ".join(f"{n} {v}" for n, v in sorted(packages.items())) + "."
        )
        planners = []
        used = set().union(*(_engines(r) for r in rows))
        for planner, dists in PLANNER_PACKAGES.items():
            if used and planner not in used:
                continue
            found = [f"{d} {packages[d]}" for d in dists if d in packages]
            if found:
                planners.append(f"{planner} ({', '.join(found)})")
        lines.append("- Planners: " + "; ".join(planners) + ".")
    return [*lines, ""]


def _placement_lines(rows: list[dict[str, str]]) -> list[str]:
    """Where the runs ran, from the rows themselves (each row's host and CPU model)."""
    runs: dict[tuple[str, str], int] = defaultdict(int)
    for row in rows:
        runs[(row.get("host") or "", row.get("cpu_model") or "")] += 1
    if not runs:
        return []
    places = [
        f"`{host}` ({cpu or 'CPU not recorded'}): {count}"
        for (host, cpu), count in sorted(runs.items())
        if host
    ]
    unknown = sum(count for (host, _), count in runs.items() if not host)
    if unknown:
        places.append(f"not recorded (a run that took its worker down, or an older row): {unknown}")
    return ["- Runs per machine (host, CPU model: runs): " + "; ".join(places) + "."]


#: Engines that plan temporal problems (a run that used one played a timeline).
TEMPORAL_ENGINES = frozenset({"kairos", "tamer", "enhsp"})


def _engines(row: dict[str, str]) -> set[str]:
    """The engines that found a run's plans (the ``planner`` column, ``a+b``)."""
    return {e for e in (row.get("planner") or "").split("+") if e}


def _planner_text(approach: str, rows: list[dict[str, str]]) -> str:
    planner = APPROACHES[approach][1]
    if planner != "auto":
        return planner
    used = set().union(*(_engines(r) for r in rows if r["approach"] == approach))
    return "auto: " + ", ".join(sorted(used)) if used else "auto"


def write_report(
    rows: list[dict[str, str]],
    out: Path,
    authoring: list[dict[str, Any]],
    command: str,
    *,
    fault_models: dict[str, dict[str, float]] | None = None,
) -> Path:
    summary = summarise_results(rows)
    comparisons = compare_approaches(rows)
    orders = summarise_orders(rows)
    _write_csv(out / "summary.csv", summary)
    _write_csv(out / "comparisons.csv", comparisons)
    _write_csv(out / "authoring.csv", authoring)
    if orders:
        _write_csv(out / "orders.csv", orders)
    figures = draw_figures(summary, rows, out)
    lines = [
        "# Scripted vs planned: study report",
        "",
        f"Command: `{command}`",
        "",
        f"{len(rows)} runs. Success = the goal holds in the simulated world at the end "
        "(for a run of an orders file: every order that arrived is done, refused or "
        "cancelled, none failed or left open). "
        "Intervals are 95%: Wilson for success rates, Newcombe for their differences, "
        "order statistics for medians. Times and steps are over successful runs only "
        "(a failed run stops early); 'n/a' where no run succeeded.",
        "",
    ]
    lines += _setup_section(rows, summary, out, fault_models or {})
    lines += ["## Findings", ""]
    lines += _findings(summary, authoring, rows)
    lines += [
        "",
        "## Success rate by fault rate",
        "",
        "| target | approach | fault rate | runs | goal reached | 95% CI | median wall time of successful runs (s) [95% CI] | mean wall time, all runs (s) | mean sim time of successful runs (s) | mean distance driven (m) | mean battery used (%) | planning share | planner calls/run | replans/run | repairs/run |",
        "|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for s in summary:
        name = _cell_name(s)
        median = (
            NA
            if s["median_wall_time_s"] == NA
            else f"{s['median_wall_time_s']:.3f} [{s['median_wall_ci_low']:.3f}, {s['median_wall_ci_high']:.3f}]"
        )
        lines.append(
            f"| {name} | {s['approach']} | {s['fault_rate']:g} | {s['runs']} | "
            f"{s['success_rate'] * 100:.0f}% | {s['ci_low'] * 100:.0f}-{s['ci_high'] * 100:.0f}% | "
            f"{median} | {s['mean_wall_time_all_s']:.3f} | {_num(s['mean_sim_time_s'], '.1f')} | "
            f"{_reported(s['mean_distance_m'], '.1f')} | {_reported(s['mean_battery_used'], '.1f')} | "
            f"{s['planning_share'] * 100:.0f}% | {s['mean_planner_calls']:.2f} | "
            f"{s['mean_replans']:.2f} | {s['mean_repairs']:.2f} |"
        )
    lines += order_section(orders)
    lines += _comparison_section(comparisons)
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
    for n, figure in enumerate(figures, 1):
        lines += [
            f"![{figure.title}]({figure.stem}.png)",
            "",
            f"*Figure {n}. {figure.title}.* {figure.caption} "
            f"([SVG]({figure.stem}.svg), PNG at 200 dpi)",
            "",
        ]
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _cell_name(row: dict[str, Any]) -> str:
    """The target of a table row, with its variant of the world and its orders file when
    it has them."""
    return cell_label(str(row["target"]), row["variant"], row.get("orders") or "")


def _comparison_section(comparisons: list[dict[str, Any]]) -> list[str]:
    if not comparisons:
        return []
    lines = [
        "",
        f"## Comparisons with `{comparisons[0]['reference']}`",
        "",
        "Per cell, each approach against the reference: success rate (Fisher's exact "
        "test; difference reference - approach with Newcombe's 95% interval) and the "
        "wall and simulated times of successful runs (medians with 95% intervals, "
        "Mann-Whitney U with tie correction). p-values are two-sided; p (Holm) adjusts "
        "them over this whole table. Also in `comparisons.csv`.",
        "",
        "| target | fault rate | approach | metric | n (ref / approach) | reference | approach | difference | test | p | p (Holm) |",
        "|---|---:|---|---|---|---|---|---|---|---:|---:|",
    ]
    for c in comparisons:
        name = _cell_name(c)
        lines.append(
            f"| {name} | {c['fault_rate']:g} | {c['approach']} | {c['metric']} | "
            f"{c['n_reference']} / {c['n_approach']} | {c['value_reference']} | "
            f"{c['value_approach']} | {c['difference']} | {c['test'] or NA} | "
            f"{format_p(c['p'])} | {format_p(c['p_holm'])} |"
        )
    return lines


def _findings(
    summary: list[dict[str, Any]], authoring: list[dict[str, Any]], rows: list[dict[str, str]]
) -> list[str]:
    out: list[str] = []
    by = {
        (s["target"], s["variant"], s["orders"], s["approach"], s["fault_rate"]): s for s in summary
    }
    targets = sorted({(s["target"], s["variant"], s["orders"]) for s in summary})
    for target, variant, orders in targets:
        rates = sorted(
            {
                s["fault_rate"]
                for s in summary
                if (s["target"], s["variant"], s["orders"]) == (target, variant, orders)
            }
        )
        if not rates:
            continue
        top = rates[-1]
        name = cell_label(target, variant, orders)
        parts = []
        for approach in APPROACHES:
            s = by.get((target, variant, orders, approach, top))
            if s:
                parts.append(
                    f"{approach} {s['success_rate'] * 100:.0f}% ({s['ci_low'] * 100:.0f}-{s['ci_high'] * 100:.0f}%)"
                )
        what = "every order accounted for (none failed or lost)" if orders else "goal reached"
        out.append(f"- **{name}**, fault rate {top:g}: {what} by " + ", ".join(parts) + ".")
        planned = by.get((target, variant, orders, "planned", top))
        scripted = by.get((target, variant, orders, "scripted", top))
        if planned and scripted:
            mine = [
                r
                for r in rows
                if (r["target"], r["variant"], r.get("orders") or "") == (target, variant, orders)
            ]
            # A robot's world (it reports distances) keeps its own simulated clock.
            timed = any(_engines(r) & TEMPORAL_ENGINES for r in mine) and not any(
                r.get("distance_m") for r in mine
            )
            out.append(
                f"  Median wall time of successful runs: planned "
                f"{_seconds(planned['median_wall_time_s'], '.2f')} "
                f"({planned['planning_share'] * 100:.0f}% of all planned runs' time is planning), "
                f"scripted {_seconds(scripted['median_wall_time_s'], '.3f')}"
                + (
                    f" (a temporal mission: both include playing the timeline at "
                    f"{TEMPORAL_TIME_SCALE:g} wall s per plan second; its sim time is the "
                    "executed makespan in plan seconds, measured on the wall clock)."
                    if timed
                    else "."
                )
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
