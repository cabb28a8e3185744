"""The scripted-vs-planned study (``plan-bridge study``).

:mod:`~plan_bridge.study.runs` runs every (mission, approach, fault rate, seed) in
worker processes and appends one row per run to ``results.csv`` (resumable);
:mod:`~plan_bridge.study.report` turns the rows into ``summary.csv``,
``authoring.csv``, plots and ``report.md``. The command line is
:mod:`plan_bridge.cli.study`.
"""

from __future__ import annotations

from plan_bridge.study.report import authoring_cost, summarise_results, wilson, write_report
from plan_bridge.study.runs import APPROACHES, RunSpec, read_results, run_one, run_study

__all__ = [
    "APPROACHES",
    "RunSpec",
    "authoring_cost",
    "read_results",
    "run_one",
    "run_study",
    "summarise_results",
    "wilson",
    "write_report",
]
