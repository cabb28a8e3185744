"""Running a study: the runs ``results.csv`` lacks, each row appended as it comes.

:func:`run_study` runs every (target, approach, fault rate, seed) in local worker
processes (the pool here: a stuck run is killed at its time limit and recorded) or,
with ``cluster=``, as Dask tasks (:mod:`plan_bridge.study.cluster`), and appends one
row per finished run to ``DIR/results.csv`` (flushed and synced: a killed study
continues where it stopped, and a run is never written twice). One run is
:func:`~plan_bridge.study.runs.run_one`.
"""

from __future__ import annotations

import csv
import multiprocessing
import os
import queue
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plan_bridge.study.cluster import DaskPool
from plan_bridge.study.runs import FIELDS, RunSpec, failure_row, pin_hash_seed, placement, run_one

__all__ = ["read_results", "run_study"]


def _row_key(row: dict[str, str]) -> tuple[str, str, str, str, str, str, str]:
    """A row's :attr:`RunSpec.key` (a row of an older version has no orders: "")."""
    return (
        row["target"],
        row["problem"],
        row["variant"],
        row.get("orders") or "",
        row["approach"],
        f"{float(row['fault_rate']):g}",
        row["seed"],
    )


# -- the worker pool ----------------------------------------------------------------------------
def _worker(tasks: Any, results: Any) -> None:
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    pin_hash_seed()
    from plan_bridge.planning.planner import get_planner

    # Start the planner's worker process now, so the first run is not charged for it.
    get_planner("fast-downward").warm_up()
    while True:
        item = tasks.get()
        if item is None:
            return
        index, spec = item
        row = run_one(spec)
        row.update(placement(f"local pid {os.getpid()}"))
        results.put((index, row))


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
            row = failure_row(
                spec,
                "timeout" if overran else "crashed",
                f"run exceeded {run_timeout:g} s"
                if overran
                else f"worker died (exit {worker.process.exitcode})",
                now - worker.since,
            )
            row.update(placement(f"local pid {worker.process.pid}"))
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


def _upgrade_header(path: Path) -> None:
    """Rewrite a ``results.csv`` of an older version with the current columns."""
    if not path.exists() or path.stat().st_size == 0:
        return
    with path.open(newline="", encoding="utf-8") as f:
        header = next(csv.reader(f), [])
    if header == FIELDS:
        return
    unknown = [h for h in header if h not in FIELDS]
    if unknown:
        raise ValueError(
            f"{path}: columns {unknown} are not study columns; is this a study's results.csv?"
        )
    rows = read_results(path)
    tmp = path.with_suffix(".csv.tmp")
    with tmp.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows([{k: r.get(k) or "" for k in FIELDS} for r in rows])
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def run_study(
    specs: Sequence[RunSpec],
    out: Path,
    *,
    jobs: int = 2,
    run_timeout: float = 300.0,
    progress: Any = None,
    cluster: str | None = None,
) -> list[dict[str, str]]:
    """Run what ``results.csv`` in ``out`` does not have yet; return every requested row.

    ``cluster`` (``tcp://HOST:PORT`` or ``local:N``) runs each run as a Dask task
    (:mod:`plan_bridge.study.cluster`); without it, ``jobs`` local worker processes do.
    """
    from plan_bridge.study.environment import machine_info, record_session
    from smach.introspection.journal import drop_torn_line

    out.mkdir(parents=True, exist_ok=True)
    results_path = out / "results.csv"
    drop_torn_line(results_path)
    _upgrade_header(results_path)
    existing = read_results(results_path)
    done = {_row_key(r) for r in existing}
    todo = [s for s in specs if s.key not in done]
    unique_todo = list({s.key: s for s in reversed(todo)}.values())[::-1]
    new_file = not results_path.exists() or results_path.stat().st_size == 0
    started = time.monotonic()
    finished = 0
    with results_path.open("a", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        if new_file:
            writer.writeheader()

        def on_result(spec: RunSpec, row: dict[str, Any]) -> None:
            nonlocal finished
            if spec.key in done:
                return  # never write a run twice, whatever the executor delivers
            done.add(spec.key)
            writer.writerow(row)
            f.flush()
            os.fsync(f.fileno())
            finished += 1
            if progress is not None:
                progress(finished, len(unique_todo), spec, row, time.monotonic() - started)

        if unique_todo:
            pool: Any
            if cluster:
                targets = sorted({str(Path(s.target).resolve()) for s in unique_todo})
                pool = DaskPool(cluster, targets)
                record_session(out, executor=f"dask {cluster}", workers=pool.workers)
            else:
                jobs = max(1, min(jobs, len(unique_todo)))
                pool = _Pool(jobs)
                # Local workers run on this machine: one description stands for all.
                record_session(
                    out, executor=f"local, {jobs} processes", workers={"local": machine_info()}
                )
            try:
                pool.run(unique_todo, run_timeout, on_result)
            finally:
                pool.close()
    wanted = {s.key for s in specs}
    rows = [r for r in read_results(results_path) if _row_key(r) in wanted]
    # A resumed study may hold a row twice if a crash hit between write and fsync: keep one.
    unique: dict[tuple[str, ...], dict[str, str]] = {}
    for row in rows:
        unique.setdefault(_row_key(row), row)
    return list(unique.values())
