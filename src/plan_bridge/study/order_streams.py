"""Order streams in the study: the numbers, comparisons, plot and report section of the
runs that serve an orders file (``plan-bridge study TARGET --orders steady,rush``).

A run of an orders file is not a success or a failure as a whole: it serves some
orders and not others. Its row holds :data:`~plan_bridge.study.runs.ORDER_FIELDS`; here
every run counts (not only those that reached "the goal"):

- :func:`summarise_orders`: per cell (target, variant, orders file, approach, fault
  rate) the orders pooled over the runs (done, failed, refused, lost, late, done the
  moment they arrived), the share done, and per run medians of latency p50 and p95,
  means of orders per hour, distance driven and busy share (``orders.csv``);
- :func:`order_comparisons`: each approach against the reference on the per-run share
  of orders done, latency p50, latency p95, orders per hour and distance: medians with
  95% intervals and the Mann-Whitney U test (rows of ``comparisons.csv``);
- :func:`draw_order_figure`: every run's values, one panel per metric and cell;
- :func:`order_section`: the report's table.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from plan_bridge.study.cells import NA, cell_columns, cells, errors, median_comparison
from plan_bridge.study.runs import APPROACHES, cell_label, cell_number
from plan_bridge.study.statistics import median_ci

__all__ = [
    "ORDER_METRICS",
    "draw_order_figure",
    "order_comparisons",
    "order_rows",
    "order_section",
    "summarise_orders",
]

#: metric -> (column of results.csv, label); ``done_share`` is orders done / arrived.
ORDER_METRICS = {
    "orders_done": ("done_share", "orders done (% of those that arrived, per run)"),
    "latency_p50": ("latency_p50_s", "latency p50 (s, arrival to done)"),
    "latency_p95": ("latency_p95_s", "latency p95 (s)"),
    "orders_per_hour": ("orders_per_hour", "orders done per hour"),
    "distance": ("distance_m", "distance driven (m)"),
}


def order_rows(rows: Iterable[dict[str, str]]) -> list[dict[str, str]]:
    """The rows of runs that served an orders file."""
    return [r for r in rows if r.get("orders")]


def per_run(row: dict[str, str], column: str) -> float | None:
    """A run's value of a metric column (None when the run has none: no order done)."""
    if column == "done_share":
        arrived = cell_number(row.get("orders_arrived", ""))
        return 100.0 * cell_number(row.get("orders_done", "")) / arrived if arrived else None
    text = row.get(column) or ""
    try:
        return float(text)
    except ValueError:
        return None


def _values(rows: Sequence[dict[str, str]], column: str) -> list[float]:
    return [v for r in rows if (v := per_run(r, column)) is not None]


def _median(values: list[float]) -> tuple[float | str, float | str, float | str]:
    if not values:
        return (NA, NA, NA)
    return tuple(round(v, 3) for v in median_ci(values))  # type: ignore[return-value]


def summarise_orders(rows: Iterable[dict[str, str]]) -> list[dict[str, Any]]:
    """One row per cell of runs that served an orders file (see the module doc)."""
    summary: list[dict[str, Any]] = []
    for cell, by_approach in sorted(cells(order_rows(rows)).items()):
        for approach, items in sorted(by_approach.items(), key=lambda kv: _rank(kv[0])):

            def total(column: str, items: list[dict[str, str]] = items) -> int:
                return int(sum(cell_number(r.get(column, "")) for r in items))

            def mean(column: str, items: list[dict[str, str]] = items) -> float | str:
                values = _values(items, column)
                return round(sum(values) / len(values), 3) if values else NA

            arrived = total("orders_arrived")
            p50 = _median(_values(items, "latency_p50_s"))
            p95 = _median(_values(items, "latency_p95_s"))
            summary.append(
                {
                    **cell_columns(cell, approach, items),
                    "errors": errors(items),
                    "orders_arrived": arrived,
                    "orders_done": total("orders_done"),
                    "done_share": round(total("orders_done") / arrived, 4) if arrived else NA,
                    "orders_failed": total("orders_failed"),
                    "orders_refused": total("orders_refused"),
                    "orders_cancelled": total("orders_cancelled"),
                    "orders_lost": total("orders_lost"),
                    "orders_late": total("orders_late"),
                    "orders_done_at_arrival": total("orders_done_at_arrival"),
                    "median_latency_p50_s": p50[0],
                    "latency_p50_ci_low": p50[1],
                    "latency_p50_ci_high": p50[2],
                    "median_latency_p95_s": p95[0],
                    "latency_p95_ci_low": p95[1],
                    "latency_p95_ci_high": p95[2],
                    "mean_orders_per_hour": mean("orders_per_hour"),
                    "mean_distance_m": mean("distance_m"),
                    "mean_busy_share": mean("busy_share"),
                }
            )
    return summary


def _rank(approach: str) -> tuple[int, str]:
    known = list(APPROACHES)
    return (known.index(approach) if approach in known else 99, approach)


def order_comparisons(
    ref_rows: Sequence[dict[str, str]], other_rows: Sequence[dict[str, str]]
) -> list[dict[str, Any]]:
    """The order metrics of one cell, ``other_rows`` against the reference's ``ref_rows``
    (every run counts; a run without a value, e.g. no order done, has no latency)."""
    return [
        median_comparison(metric, _values(ref_rows, column), _values(other_rows, column))
        for metric, (column, _) in ORDER_METRICS.items()
    ]


def _pct(value: Any) -> str:
    return NA if value == NA else f"{100 * value:.1f}%"


def _num(value: Any, fmt: str) -> str:
    return NA if value == NA else format(value, fmt)


def order_section(summary: list[dict[str, Any]]) -> list[str]:
    """The report's "Order streams" section (nothing without order runs)."""
    if not summary:
        return []
    lines = [
        "",
        "## Order streams",
        "",
        "Runs that served an orders file (`--orders`), every run counted. Orders are "
        "pooled over the runs of a cell: done (share of those that arrived), failed, "
        "refused (never accepted: a goal no robot could reach, with the reason), lost "
        "(still open at the end: should be 0), late (done after the deadline), done at "
        "arrival (their goal held already). Latency is arrival to done: the median over "
        "runs of each run's p50 and p95, with 95% intervals. Orders per hour, distance "
        "and busy share (the robots' mean share of the mission's time at work) are means "
        "over runs. Also in `orders.csv`.",
        "",
        "| cell | fault rate | approach | runs | orders | done | failed | refused | lost "
        "| late | done at arrival | latency p50 (s) [95% CI] | latency p95 (s) [95% CI] "
        "| orders/h | distance (m) | busy share |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for s in summary:
        p50 = (
            NA
            if s["median_latency_p50_s"] == NA
            else f"{s['median_latency_p50_s']:.1f} [{s['latency_p50_ci_low']:.1f}, "
            f"{s['latency_p50_ci_high']:.1f}]"
        )
        p95 = (
            NA
            if s["median_latency_p95_s"] == NA
            else f"{s['median_latency_p95_s']:.1f} [{s['latency_p95_ci_low']:.1f}, "
            f"{s['latency_p95_ci_high']:.1f}]"
        )
        lines.append(
            f"| {cell_label(s['target'], s['variant'], s['orders'])} | {s['fault_rate']:g} | "
            f"{s['approach']} | {s['runs']} | {s['orders_arrived']} | {s['orders_done']} "
            f"({_pct(s['done_share'])}) | {s['orders_failed']} | {s['orders_refused']} | "
            f"{s['orders_lost']} | {s['orders_late']} | {s['orders_done_at_arrival']} | {p50} | "
            f"{p95} | {_num(s['mean_orders_per_hour'], '.1f')} | "
            f"{_num(s['mean_distance_m'], '.0f')} | {_num(s['mean_busy_share'], '.3f')} |"
        )
    return lines


def draw_order_figure(
    rows: list[dict[str, str]], out: Path, style: dict[str, dict[str, str]]
) -> tuple[str, str, str] | None:
    """Every order run's share done, latency p50 and p95, orders per hour and distance:
    one column per cell, one row per metric, one point per run. The plot's (stem, title,
    caption); None without order runs."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    mine = order_rows(rows)
    if not mine:
        return None
    cells = sorted(
        {(r["target"], r["variant"], r["orders"], cell_number(r["fault_rate"])) for r in mine}
    )
    approaches = sorted({r["approach"] for r in mine}, key=_rank)
    fig, axes = plt.subplots(
        len(ORDER_METRICS),
        len(cells),
        figsize=(3.2 * len(cells) + 1.2, 2.1 * len(ORDER_METRICS) + 0.8),
        squeeze=False,
        sharex=True,
    )
    for col, (target, variant, orders, rate) in enumerate(cells):
        cell = [
            r
            for r in mine
            if (r["target"], r["variant"], r["orders"], cell_number(r["fault_rate"]))
            == (target, variant, orders, rate)
        ]
        for row_i, (column, label) in enumerate(ORDER_METRICS.values()):
            ax = axes[row_i][col]
            for i, approach in enumerate(approaches):
                values = _values([r for r in cell if r["approach"] == approach], column)
                n = len(values)
                xs = [i + 0.3 * (k / max(1, n - 1) - 0.5) for k in range(n)]
                ax.scatter(xs, values, s=10, alpha=0.75, linewidths=0, **style[approach])
                if values:
                    middle = median_ci(values)[0]
                    ax.plot([i - 0.3, i + 0.3], [middle, middle], color="black", linewidth=1)
            ax.set_xticks(range(len(approaches)), approaches, fontsize=8)
            ax.set_xlim(-0.6, len(approaches) - 0.4)
            ax.grid(axis="y", alpha=0.3)
            if col == 0:
                ax.set_ylabel(label, fontsize=7)
            if row_i == 0:
                title = cell_label(target, variant, orders)
                ax.set_title(f"{title}\nfault rate {rate:g}", fontsize=8)
    handles = [
        Line2D([], [], linestyle="", color=style[a]["color"], marker=style[a]["marker"], label=a)
        for a in approaches
    ]
    handles.append(Line2D([], [], color="black", linewidth=1, label="median"))
    fig.legend(
        handles,
        [str(h.get_label()) for h in handles],
        loc="lower center",
        ncol=len(handles),
        bbox_to_anchor=(0.5, -0.01),
        frameon=False,
        fontsize=8,
    )
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    stem = "orders_per_run"
    fig.savefig(out / f"{stem}.png", dpi=200, bbox_inches="tight")
    fig.savefig(out / f"{stem}.svg", bbox_inches="tight")
    plt.close(fig)
    return (
        stem,
        "Orders served, per run",
        "Every run of an orders file is one point per panel (nothing is averaged; the bar "
        "is the median): the share of the orders that arrived that were done, latency p50 "
        "and p95 (arrival to done, seconds of the mission's clock), orders done per hour, "
        "and the distance the robots drove, per cell (target, world variant, orders file, "
        "fault rate) and approach. The runs of a cell have the same seeds, so both "
        "approaches meet the same orders at the same times and the same faults.",
    )
