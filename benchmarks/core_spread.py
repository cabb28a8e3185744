"""core_bench.py over fresh processes: each scenario's spread between processes (issue 39).

A figure measured in one process can be that process's luck. Nested machines once ran
at one of two speeds, up to 2x apart, depending on the process: steady within it, not
between processes (CPython's frame stack crossing a chunk boundary on every execution,
as often as the caller's stack depth made it; docs/performance.md, "Nested machines").
So ``core_bench.py`` measures in N fresh processes (``--processes``, default 6), one
after the other, each a complete ``core_bench.py --processes 1`` run that writes its
JSON, and this module puts them together:

* every scenario of the table: the median of each process, the best and the worst
  process, the median over processes, and the spread (worst / best - 1). Aim of issue
  39: each nesting scenario (``nested*``) within 10% of its best process;
* against the original (``--original``), each cell (scenario, mode, logging
  configuration): our median over processes and its spread, the original's, and the
  ratio (original / ours, paired per round as in core_compare.py) in every process; the
  aims of core_compare.py are judged on the lowest ratio of any process ("in every run").
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import core_compare

#: The spread aim of issue 39, for the scenarios named here (prefixes).
SPREAD_AIM = 0.10
SPREAD_AIMED = ("nested",)


def run(
    script: Path,
    worker_args: list[str],
    processes: int,
    cfg: Any,
    json_out: str | None,
    progress: Callable[[str], None],
    units: dict[str, str],
) -> int:
    """Run ``script`` (core_bench.py) in ``processes`` fresh processes, one after the
    other, and report the spread (``units``: each scenario's unit); write everything to
    ``json_out`` if given."""
    docs: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="core_spread-") as tmp:
        for i in range(processes):
            out = Path(tmp) / f"process{i + 1}.json"
            cmd = [sys.executable, str(script), *worker_args, "--processes", "1"]
            cmd += ["--json", str(out)]
            progress(f"fresh process {i + 1}/{processes}: {' '.join(cmd[1:])}")
            proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
            if proc.returncode != 0:
                sys.stderr.write(proc.stdout + proc.stderr)
                progress(f"process {i + 1} failed (exit {proc.returncode})")
                return proc.returncode
            docs.append(json.loads(out.read_text(encoding="utf-8")))
    lines, summary = report(docs, cfg, units)
    print("\n".join(lines), flush=True)
    if json_out:
        doc = {"mode": docs[0]["mode"], "processes": processes, **summary, "runs": docs}
        Path(json_out).write_text(json.dumps(doc, indent=2), encoding="utf-8")
        progress(f"wrote {json_out}")
    return 0


def _fmt(value: float) -> str:
    if value >= 100:
        return f"{value:.0f}"
    if value >= 10:
        return f"{value:.1f}"
    if value >= 1:
        return f"{value:.2f}"
    return f"{value:.3f}"


def report(
    docs: list[dict[str, Any]], cfg: Any, units: dict[str, str]
) -> tuple[list[str], dict[str, Any]]:
    """The lines of the spread report and its JSON summary."""
    n = len(docs)
    loads = [d["load_average_1min"]["before"] for d in docs]
    lines = [
        "",
        f"smach core benchmark - {docs[0]['mode']} mode, {n} fresh processes, one after the "
        f"other (python {docs[0]['python']}, {docs[0]['cores']} cores; 1-min load at the "
        f"start of each: {' '.join(f'{x:.1f}' for x in loads)})",
        "",
        "Spread over the processes (each process: the median of its trials; spread = worst "
        "/ best - 1):",
        "",
    ]
    rows = spread_rows(docs, units)
    head = f"{'scenario':<18} {'unit':<14} {'best':>8} {'median':>8} {'worst':>8} {'spread':>7}  each process"
    lines += [head, "-" * len(head)]
    for row in rows:
        scale = 1000.0 if row["unit"].startswith("ns") else 1.0
        each = " ".join(_fmt(v * scale) for v in row["per_process"])
        lines.append(
            f"{row['scenario']:<18} {row['unit']:<14} {_fmt(row['best'] * scale):>8} "
            f"{_fmt(row['median'] * scale):>8} {_fmt(row['worst'] * scale):>8} "
            f"{row['spread'] * 100:>6.1f}%  {each}"
        )
    aims: list[dict[str, Any]] = []
    aimed = [row for row in rows if row["scenario"].startswith(SPREAD_AIMED)]
    if aimed:
        lines += [
            "",
            f"Aim (issue 39): each nesting scenario within {SPREAD_AIM:.0%} of its best process:",
        ]
        for row in aimed:
            ok = row["spread"] <= SPREAD_AIM
            aims.append({"aim": f"{row['scenario']} spread", "pass": ok, "spread": row["spread"]})
            lines.append(
                f"  {'PASS' if ok else 'MISS'}  {row['scenario']:<18} {row['spread'] * 100:.1f}%"
            )
    summary: dict[str, Any] = {"spread": rows, "spread_aims": aims}
    if docs[0].get("original_same_run"):
        more, summary["original"] = comparison(docs, cfg)
        lines += more
    return lines, summary


def spread_rows(docs: list[dict[str, Any]], units: dict[str, str]) -> list[dict[str, Any]]:
    """Per scenario of the table: each process's median, best, median, worst, spread."""
    rows = []
    for name in docs[0]["results"]:
        per_process = [d["results"][name]["median"] for d in docs]
        best, worst = min(per_process), max(per_process)
        rows.append(
            {
                "scenario": name,
                "unit": units.get(name, "us"),
                "per_process": per_process,
                "best": best,
                "median": statistics.median(per_process),
                "worst": worst,
                "spread": worst / best - 1 if best > 0 else float("inf"),
            }
        )
    return rows


def comparison(docs: list[dict[str, Any]], cfg: Any) -> tuple[list[str], dict[str, Any]]:
    """Against the original: every cell over the processes, and the aims on the lowest."""
    configs = core_compare.CONFIGS
    lines = [
        "",
        f"Against the original SMACH core, measured in each process (ours and the original's "
        f"trials interleaved); ratio = original / ours, paired per round, in each of the "
        f"{len(docs)} processes:",
        "",
    ]
    head = (
        f"{'scenario':<16} {'mode':<9} {'config':<8} {'ours best-worst (spread)':>28} "
        f"{'original':>9} {'ratio min':>9} {'median':>7} {'max':>6}"
    )
    lines += [head, "-" * len(head)]
    cells: list[dict[str, Any]] = []
    same_run = [d["original_same_run"] for d in docs]
    for key in same_run[0][configs[0]]:
        scenario, mode, impl = key.split("/")
        if impl != "ours":
            continue
        for config in configs:
            ours = [s[config][key] for s in same_run]
            theirs = [s[config].get(f"{scenario}/{mode}/original") for s in same_run]
            medians = [o["median"] for o in ours]
            cell: dict[str, Any] = {
                "scenario": scenario,
                "mode": mode,
                "config": config,
                "ours": medians,
                "ours_spread": max(medians) / min(medians) - 1,
                "original": [t["median"] for t in theirs if t],
                "ratios": [
                    core_compare.paired_ratio(_samples(t), _samples(o))
                    for o, t in zip(ours, theirs, strict=True)
                    if t
                ],
            }
            cells.append(cell)
            ratios = cell["ratios"]
            shown = (
                f"{min(ratios):>8.1f}x {statistics.median(ratios):>6.1f}x {max(ratios):>5.1f}x"
                if ratios
                else f"{'-':>9} {'-':>7} {'-':>6}"
            )
            original = (
                f"{statistics.median(cell['original']):>9.4g}" if cell["original"] else f"{'-':>9}"
            )
            span = f"{_fmt(min(medians))}-{_fmt(max(medians))} ({cell['ours_spread'] * 100:.1f}%)"
            lines.append(f"{scenario:<16} {mode:<9} {config:<8} {span:>28} {original} {shown}")
    lines += ["", "Aims (every logging configuration and mode, in every process):"]
    aims = []
    for name, factor in core_compare.SPEEDUP_AIMS.items():
        for mode in ("repeated", "first"):
            mine = [c for c in cells if c["scenario"] == name and c["mode"] == mode and c["ratios"]]
            if not mine:
                continue
            low = min(mine, key=lambda c: min(c["ratios"]))
            lowest = min(low["ratios"])
            ok = lowest >= factor
            where = f"process {low['ratios'].index(lowest) + 1}, {low['config']}"
            aims.append({"aim": f"{name} ({mode})", "factor": factor, "lowest": lowest, "pass": ok})
            lines.append(
                f"  {'PASS' if ok else 'MISS'}  {name} ({mode}): >= {factor:g}x the original in "
                f"every process{'':<4} lowest {lowest:.1f}x ({where})"
            )
    return lines, {"cells": cells, "aims": aims}


def _samples(result: dict[str, Any]) -> SimpleNamespace:
    return SimpleNamespace(samples=result["samples"])
