"""The scripted-vs-planned study (``plan-bridge study``).

:mod:`~plan_bridge.study.schedule` runs every (mission, approach, fault rate, seed) in
local worker processes and appends one row per run to ``results.csv`` (resumable;
one run is :mod:`~plan_bridge.study.runs`);
:mod:`~plan_bridge.study.cluster` runs them as tasks on a Dask distributed cluster
instead (imported only with ``--cluster``); :mod:`~plan_bridge.study.environment`
records what ran them. :mod:`~plan_bridge.study.report` turns the rows into
``summary.csv``, ``comparisons.csv`` (:mod:`~plan_bridge.study.comparison`, with the
tests of :mod:`~plan_bridge.study.statistics`), ``authoring.csv``, plots
(:mod:`~plan_bridge.study.figures`) and ``report.md``. The command line is
:mod:`plan_bridge.cli.study`.
"""

from __future__ import annotations

from plan_bridge.study.comparison import compare_approaches
from plan_bridge.study.report import authoring_cost, summarise_results, wilson, write_report
from plan_bridge.study.runs import APPROACHES, VARYING_FIELDS, RunSpec, run_one
from plan_bridge.study.schedule import read_results, run_study

__all__ = [
    "APPROACHES",
    "VARYING_FIELDS",
    "RunSpec",
    "authoring_cost",
    "compare_approaches",
    "read_results",
    "run_one",
    "run_study",
    "summarise_results",
    "wilson",
    "write_report",
]
