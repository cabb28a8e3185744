"""Approaches compared with a reference approach, cell by cell, with intervals and p-values.

A *cell* is (target, variant, orders file, fault rate). In each cell every approach is
compared with the reference (``planned`` by default) on three metrics:

- success rate: both rates with Wilson intervals, the difference with Newcombe's
  interval, Fisher's exact test;
- wall time and simulated robot time of successful runs: both medians with
  order-statistic intervals, the Mann-Whitney U test. Only successful runs are
  compared (a failed run stops early, so its time is not the cost of the mission);
  the success rate comparison above is what accounts for the failures. Where either
  approach has no successful run the comparison is "n/a".

A cell of runs that served an orders file is compared on the order metrics of
:mod:`~plan_bridge.study.order_streams` too (share of orders done, latency p50 and p95,
orders per hour, distance: every run counts).

p-values are two-sided; ``p_holm`` adjusts them with Holm's method over the whole
table (every metric, cell and approach), for a reader who wants one family.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from plan_bridge.study.cells import NA, cells, median_comparison
from plan_bridge.study.order_streams import order_comparisons
from plan_bridge.study.runs import cell_number
from plan_bridge.study.statistics import fisher_exact, holm, newcombe, wilson

__all__ = ["METRICS", "compare_approaches", "format_p"]

#: metric name -> (column of results.csv, label)
METRICS = {
    "success": ("goal_reached", "goal reached (%)"),
    "wall_time": ("wall_time_s", "wall time of successful runs (s)"),
    "sim_time": ("sim_time_s", "simulated time of successful runs (s)"),
}


def format_p(p: float | str) -> str:
    if isinstance(p, str):
        return p
    return "<0.0001" if p < 1e-4 else f"{p:.4f}"


def compare_approaches(
    rows: Iterable[dict[str, str]], reference: str = "planned"
) -> list[dict[str, Any]]:
    """One row per (cell, approach other than ``reference``, metric)."""
    out: list[dict[str, Any]] = []
    for (target, variant, orders, rate), by_approach in sorted(cells(rows).items()):
        ref_rows = by_approach.get(reference)
        if not ref_rows:
            continue
        for approach, other_rows in by_approach.items():
            if approach == reference:
                continue
            base = {
                "target": target,
                "variant": variant,
                "orders": orders,
                "fault_rate": rate,
                "reference": reference,
                "approach": approach,
            }
            rs = sum(1 for r in ref_rows if r["goal_reached"] == "True")
            os_ = sum(1 for r in other_rows if r["goal_reached"] == "True")
            rn, on = len(ref_rows), len(other_rows)
            rl, rh = wilson(rs, rn)
            ol, oh = wilson(os_, on)
            dl, dh = newcombe(rs, rn, os_, on)
            out.append(
                {
                    **base,
                    "metric": "success",
                    "n_reference": rn,
                    "n_approach": on,
                    "value_reference": f"{100 * rs / rn:.0f}% [{100 * rl:.0f}, {100 * rh:.0f}]",
                    "value_approach": f"{100 * os_ / on:.0f}% [{100 * ol:.0f}, {100 * oh:.0f}]",
                    "difference": f"{100 * (rs / rn - os_ / on):+.0f} pp [{100 * dl:+.0f}, {100 * dh:+.0f}]",
                    "test": "Fisher exact",
                    "p": fisher_exact(rs, rn - rs, os_, on - os_),
                }
            )
            for metric in ("wall_time", "sim_time"):
                column = METRICS[metric][0]
                ref = [cell_number(r[column]) for r in ref_rows if r["goal_reached"] == "True"]
                other = [cell_number(r[column]) for r in other_rows if r["goal_reached"] == "True"]
                out.append({**base, **median_comparison(metric, ref, other)})
            if orders:
                out += [{**base, **c} for c in order_comparisons(ref_rows, other_rows)]
    tested = [i for i, c in enumerate(out) if isinstance(c["p"], float)]
    adjusted = holm([out[i]["p"] for i in tested])
    for c in out:
        c["p_holm"] = NA
    for i, p in zip(tested, adjusted, strict=True):
        out[i]["p_holm"] = p
    return out
