"""What every table of the study says of a cell, whatever it measures.

A *cell* is (target, variant, orders file, fault rate); its runs are grouped by
approach. :mod:`~plan_bridge.study.report` (``summary.csv``),
:mod:`~plan_bridge.study.order_streams` (``orders.csv``) and
:mod:`~plan_bridge.study.comparison` (``comparisons.csv``) build their rows on these:
the rows of each cell (:func:`cells`), the columns that name a row of a summary
(:func:`cell_columns`), the runs that ended in an error (:func:`errors`), and the
comparison of two approaches' medians (:func:`median_comparison`).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Sequence
from typing import Any

from plan_bridge.study.runs import cell_number
from plan_bridge.study.statistics import mann_whitney_u, median_ci

__all__ = ["NA", "Cell", "cell_columns", "cells", "errors", "median_comparison"]

NA = "n/a"
"""A value a table cannot give (no run to take it from): never 0."""

Cell = tuple[str, str, str, float]
"""(target, variant, orders file or "", fault rate)."""

Row = dict[str, str]


def cells(rows: Iterable[Row]) -> dict[Cell, dict[str, list[Row]]]:
    """The rows of ``results.csv`` by cell, then by approach."""
    grouped: dict[Cell, dict[str, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        cell = (
            row["target"],
            row["variant"],
            row.get("orders") or "",
            cell_number(row["fault_rate"]),
        )
        grouped[cell][row["approach"]].append(row)
    return grouped


def cell_columns(cell: Cell, approach: str, runs: Sequence[Row]) -> dict[str, Any]:
    """The first columns of a summary's row: which cell and approach, how many runs."""
    target, variant, orders, rate = cell
    return {
        "target": target,
        "variant": variant,
        "orders": orders,
        "approach": approach,
        "fault_rate": rate,
        "runs": len(runs),
    }


def errors(runs: Iterable[Row]) -> int:
    """How many of ``runs`` ended in an error, a timeout or a crash (no result)."""
    return sum(1 for r in runs if r["outcome"] in ("error", "timeout", "crashed"))


def median_comparison(metric: str, ref: list[float], other: list[float]) -> dict[str, Any]:
    """A row of ``comparisons.csv`` for ``metric`` (without its cell's columns): the
    medians of the reference's values ``ref`` and the approach's ``other`` with their
    95% intervals, the difference of the medians and the Mann-Whitney U test ("n/a"
    when either has no value)."""
    row: dict[str, Any] = {"metric": metric, "n_reference": len(ref), "n_approach": len(other)}
    if not ref or not other:
        return row | {
            "value_reference": NA,
            "value_approach": NA,
            "difference": NA,
            "test": "",
            "p": NA,
        }
    rm, rl, rh = median_ci(ref)
    om, ol, oh = median_ci(other)
    _, p = mann_whitney_u(ref, other)
    return row | {
        "value_reference": f"{rm:.3g} [{rl:.3g}, {rh:.3g}]",
        "value_approach": f"{om:.3g} [{ol:.3g}, {oh:.3g}]",
        "difference": f"{rm - om:+.3g} (medians)",
        "test": "Mann-Whitney U",
        "p": p,
    }
