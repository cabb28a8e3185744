"""The study's plots: PNG at 200 dpi and SVG, each with the caption the report prints.

Approaches get a fixed colour and marker each, curves are offset a little along x
so that equal values do not hide one another, and legends sit below the axes, never
on the data. The time plot shows every run (no average at all), marking whether it
reached the goal, so that nothing is hidden by averaging over successful runs only.
"""

from __future__ import annotations

import itertools
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

from plan_bridge.study.order_streams import draw_order_figure
from plan_bridge.study.runs import APPROACHES, cell_label, cell_number

__all__ = ["DPI", "Figure", "draw_figures"]

DPI = 200
MARKERS = "osD^vP*X"


class Figure:
    """A written plot: file stem (``.png`` and ``.svg`` exist) and its caption."""

    def __init__(self, stem: str, title: str, caption: str) -> None:
        self.stem = stem
        self.title = title
        self.caption = caption


def _order(approaches: set[str]) -> list[str]:
    known = list(APPROACHES)
    return sorted(approaches, key=lambda a: (known.index(a) if a in known else 99, a))


Cell = tuple[str, str, str]
"""(target, variant, orders file): a column of panels."""


def _cell(row: dict[str, Any]) -> Cell:
    return (row["target"], row["variant"], row.get("orders") or "")


def draw_figures(
    summary: list[dict[str, Any]], rows: list[dict[str, str]], out: Path
) -> list[Figure]:
    """Write the plots into ``out``; none (with a note) when matplotlib is missing."""
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
    if not summary:
        return []
    approaches = _order({s["approach"] for s in summary})
    style = {
        a: {"color": f"C{i % 10}", "marker": MARKERS[i % len(MARKERS)]}
        for i, a in enumerate(approaches)
    }
    targets = sorted({_cell(s) for s in summary})
    figures = [
        _success(summary, targets, approaches, style, out),
        _times(rows, targets, approaches, style, out),
        _planning(summary, rows, approaches, style, out),
    ]
    drawn = draw_order_figure(rows, out, style)
    if drawn is not None:
        figures.append(Figure(*drawn))
    return figures


def _save(fig: Any, out: Path, stem: str) -> None:
    import matplotlib.pyplot as plt

    fig.savefig(out / f"{stem}.png", dpi=DPI, bbox_inches="tight")
    fig.savefig(out / f"{stem}.svg", bbox_inches="tight")
    plt.close(fig)


def _legend_below(fig: Any, handles: list[Any], labels: list[str]) -> None:
    fig.legend(
        handles,
        labels,
        loc="lower center",
        ncol=min(len(labels), 6),
        bbox_to_anchor=(0.5, -0.02),
        frameon=False,
        fontsize=8,
    )


def _offsets(count: int, spread: float) -> list[float]:
    if count == 1:
        return [0.0]
    return [spread * (i / (count - 1) - 0.5) for i in range(count)]


def _success(
    summary: list[dict[str, Any]],
    targets: list[Cell],
    approaches: list[str],
    style: dict[str, dict[str, str]],
    out: Path,
) -> Figure:
    import matplotlib.pyplot as plt

    rates = sorted({s["fault_rate"] for s in summary})
    step = min((b - a for a, b in itertools.pairwise(rates)), default=0.1)
    offsets = dict(zip(approaches, _offsets(len(approaches), 0.6 * step), strict=True))
    fig, axes = plt.subplots(
        1, len(targets), figsize=(4.4 * len(targets), 3.6), squeeze=False, sharey=True
    )
    handles: dict[str, Any] = {}
    for ax, cell in zip(axes[0], targets, strict=True):
        for approach in approaches:
            pts = sorted(
                (s["fault_rate"], s["success_rate"], s["ci_low"], s["ci_high"])
                for s in summary
                if _cell(s) == cell and s["approach"] == approach
            )
            if not pts:
                continue
            xs = [p[0] + offsets[approach] for p in pts]
            ys = [p[1] * 100 for p in pts]
            err = [[(p[1] - p[2]) * 100 for p in pts], [(p[3] - p[1]) * 100 for p in pts]]
            handles[approach] = ax.errorbar(
                xs, ys, yerr=err, capsize=2, linewidth=1, markersize=4, **style[approach]
            )
        ax.set_title(cell_label(*cell), fontsize=10)
        ax.set_xlabel("fault rate")
        ax.set_xticks(rates)
        ax.set_ylim(-4, 104)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("runs that reached the goal (%)")
    _legend_below(fig, list(handles.values()), list(handles))
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    _save(fig, out, "success_vs_fault_rate")
    runs = sorted({s["runs"] for s in summary})
    per_cell = f"{runs[0]}" if len(runs) == 1 else f"{runs[0]}-{runs[-1]}"
    return Figure(
        "success_vs_fault_rate",
        "Success rate vs fault rate",
        f"Share of runs that reached the goal, per mission, approach and fault rate "
        f"({per_cell} runs per point, one per seed), with 95% Wilson intervals. "
        "Approaches are offset slightly along x so that equal values stay visible.",
    )


def _times(
    rows: list[dict[str, str]],
    targets: list[Cell],
    approaches: list[str],
    style: dict[str, dict[str, str]],
    out: Path,
) -> Figure:
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    rates = sorted({cell_number(r["fault_rate"]) for r in rows})
    offsets = dict(zip(approaches, _offsets(len(approaches), 0.7), strict=True))
    fig, axes = plt.subplots(
        2, len(targets), figsize=(4.4 * len(targets), 6.4), squeeze=False, sharex=True
    )
    for col, target in enumerate(targets):
        cell: dict[tuple[str, float], list[dict[str, str]]] = defaultdict(list)
        for r in rows:
            if _cell(r) == target:
                cell[(r["approach"], cell_number(r["fault_rate"]))].append(r)
        for row_i, (column, ylabel) in enumerate(
            (("sim_time_s", "simulated robot time (s)"), ("wall_time_s", "wall time (s, log)"))
        ):
            ax = axes[row_i][col]
            for approach in approaches:
                for i, rate in enumerate(rates):
                    items = cell.get((approach, rate), [])
                    if not items:
                        continue
                    n = len(items)
                    # spread the runs of one cell a little so that equal values stay apart
                    xs = [
                        i + offsets[approach] + 0.05 * (k / max(1, n - 1) - 0.5) for k in range(n)
                    ]
                    ys = [cell_number(r[column]) for r in items]
                    ok = [r["goal_reached"] == "True" for r in items]
                    color, marker = style[approach]["color"], style[approach]["marker"]
                    ax.scatter(
                        [x for x, o in zip(xs, ok, strict=True) if o],
                        [y for y, o in zip(ys, ok, strict=True) if o],
                        s=9,
                        color=color,
                        marker=marker,
                        alpha=0.7,
                        linewidths=0,
                    )
                    ax.scatter(
                        [x for x, o in zip(xs, ok, strict=True) if not o],
                        [y for y, o in zip(ys, ok, strict=True) if not o],
                        s=9,
                        facecolors="none",
                        edgecolors=color,
                        marker=marker,
                        alpha=0.9,
                        linewidths=0.7,
                    )
            ax.set_ylabel(ylabel, fontsize=8)
            if column == "wall_time_s":
                if any(cell_number(r[column]) > 0 for items in cell.values() for r in items):
                    ax.set_yscale("log")
                ax.set_xlabel("fault rate")
            else:
                ax.set_title(cell_label(*target), fontsize=10)
            ax.set_xticks(range(len(rates)), [f"{r:g}" for r in rates])
            ax.grid(alpha=0.3)
    handles = [
        Line2D([], [], linestyle="", color=style[a]["color"], marker=style[a]["marker"], label=a)
        for a in approaches
    ]
    handles.append(
        Line2D([], [], linestyle="", color="grey", marker="o", label="goal reached (filled)")
    )
    handles.append(
        Line2D(
            [], [], linestyle="", color="grey", marker="o", markerfacecolor="none", label="failed"
        )
    )
    _legend_below(fig, handles, [str(h.get_label()) for h in handles])
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    _save(fig, out, "time_per_run")
    return Figure(
        "time_per_run",
        "Time of every run",
        "Every run is one point (nothing is averaged): simulated robot time (top) and "
        "wall time (bottom, log scale) per mission, grouped by fault rate, one column "
        "of points per approach. Filled markers reached the goal, hollow ones did not; a "
        "failed run stops early, so its time is not the cost of the mission.",
    )


def _planning(
    summary: list[dict[str, Any]],
    rows: list[dict[str, str]],
    approaches: list[str],
    style: dict[str, dict[str, str]],
    out: Path,
) -> Figure:
    import matplotlib.pyplot as plt

    planned = [a for a in approaches if APPROACHES.get(a, ("", ""))[1]]
    rates = sorted({cell_number(r["fault_rate"]) for r in rows})
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    ax = axes[0]
    step = min((b - a for a, b in itertools.pairwise(rates)), default=0.1)
    offsets = dict(zip(planned, _offsets(len(planned), 0.4 * step), strict=True))
    for approach in planned:
        xs, ys = [], []
        for rate in rates:
            items = [
                r
                for r in rows
                if r["approach"] == approach and cell_number(r["fault_rate"]) == rate
            ]
            wall = sum(cell_number(r["wall_time_s"]) for r in items)
            if wall:
                xs.append(rate + offsets[approach])
                ys.append(100 * sum(cell_number(r["planning_time_s"]) for r in items) / wall)
        ax.plot(xs, ys, label=approach, linewidth=1, markersize=4, **style[approach])
    ax.set_xlabel("fault rate")
    ax.set_xticks(rates)
    ax.set_ylabel("planning time / wall time (%)")
    ax.set_ylim(0, 102)
    ax.set_title("Share of wall time spent planning", fontsize=10)
    ax.grid(alpha=0.3)
    ax = axes[1]
    layers = ("skill", "retry", "continue", "repair", "replan")
    bottoms = [0.0] * len(planned)
    for n, layer in enumerate(layers):
        values = []
        for approach in planned:
            items = [r for r in rows if r["approach"] == approach]
            values.append(
                sum(cell_number(r[f"absorbed_{layer}"]) for r in items) / len(items)
                if items
                else 0.0
            )
        ax.bar(planned, values, bottom=bottoms, label=layer, color=f"C{n}", alpha=0.8)
        bottoms = [b + v for b, v in zip(bottoms, values, strict=True)]
    ax.set_ylabel("faults absorbed per run")
    ax.set_xlabel("approach")
    ax.set_title("Where faults were absorbed", fontsize=10)
    ax.tick_params(axis="x", labelsize=8)
    ax.grid(axis="y", alpha=0.3)
    if planned:  # a study of scripted runs only has nothing to show here
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1), frameon=False)
        axes[0].legend(
            fontsize=8, loc="upper left", bbox_to_anchor=(0, -0.18), ncol=3, frameon=False
        )
    fig.tight_layout()
    _save(fig, out, "planning_share_and_absorption")
    return Figure(
        "planning_share_and_absorption",
        "Planning share and absorption of faults",
        "Left: total planning time divided by total wall time of all runs (successful or "
        "not) of an approach at a fault rate, pooled over the missions; the axis spans "
        "0-100%. Right: faults absorbed per run, averaged over all runs of an approach "
        "(every mission and fault rate), by the layer that absorbed them: inside a skill "
        "(never surfaced as a failed step), or by the executive's retry, continue, "
        "repair or replan.",
    )
