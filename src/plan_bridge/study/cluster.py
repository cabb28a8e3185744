"""Runs of the study as tasks on a Dask distributed cluster (``plan-bridge study --cluster``).

``--cluster tcp://HOST:PORT`` connects to a running ``dask scheduler`` and submits one
task per run to its workers; ``--cluster local:N`` starts a local cluster of N worker
processes for the duration of the study. Dask schedules the tasks and, when a worker
dies, runs that worker's tasks again on another one (up to the scheduler's
``allowed-failures``): a run's result depends only on its :class:`RunSpec`, so a
rerun writes the same row. The client, in the study's process, writes each row as
its task finishes, so resuming and "never twice" work as for a local study.

Only this module imports Dask, and only :func:`DaskPool` does so (when called): a
study without ``--cluster`` never loads it.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import re
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.study.runs import RunSpec, failure_row, pin_hash_seed, placement, run_one

__all__ = ["ClusterError", "DaskPool", "parse_cluster", "run_task"]

_INSTALL = "pip install 'smach-planner[cluster]'"
#: Seconds to wait for the scheduler to answer.
CONNECT_TIMEOUT = 15.0


class ClusterError(PlanBridgeError):
    """The cluster cannot be used: bad address, Dask missing, scheduler or workers unfit."""


def parse_cluster(text: str) -> tuple[str, str | int]:
    """``("tcp", "tcp://HOST:PORT")`` or ``("local", N)``; a clear error otherwise."""
    if text.startswith("local:"):
        count = text.removeprefix("local:")
        if not count.isdigit() or int(count) < 1:
            raise ClusterError(
                f"--cluster {text!r}: local:N needs a worker count N >= 1, e.g. local:4"
            )
        return ("local", int(count))
    if re.fullmatch(r"tcp://[^\s:/]+:\d{1,5}", text):
        return ("tcp", text)
    raise ClusterError(
        f"--cluster {text!r}: expected tcp://HOST:PORT (the address a running "
        "`dask scheduler` prints) or local:N (start N local worker processes)"
    )


# -- on a worker --------------------------------------------------------------------------------
_warmed = False


def run_task(spec: RunSpec, run_timeout: float) -> dict[str, Any]:
    """One run on a Dask worker: the row of :func:`run_one`, or a ``timeout`` row.

    The run goes in its own thread so that a stuck one is abandoned after
    ``run_timeout``; the client then restarts that worker to get rid of the thread.
    """
    global _warmed
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    pin_hash_seed()  # before the first planner process starts in this worker
    get_worker: Any = importlib.import_module("distributed").get_worker

    if not _warmed:
        from plan_bridge.planning.planner import get_planner

        # Start the planner's process now, so the first run is not charged for it.
        get_planner("fast-downward").warm_up()
        _warmed = True
    box: list[dict[str, Any]] = []
    started = time.monotonic()
    thread = threading.Thread(target=lambda: box.append(run_one(spec)), daemon=True)
    thread.start()
    thread.join(run_timeout)
    if box:
        row = box[0]
    else:
        row = failure_row(
            spec, "timeout", f"run exceeded {run_timeout:g} s", time.monotonic() - started
        )
    row.update(placement(get_worker().address))
    return row


def worker_check(targets: Sequence[str]) -> dict[str, Any]:
    """A worker's machine and which of the study's domain folders it lacks."""
    from plan_bridge.study.environment import machine_info

    info = machine_info()
    info["missing"] = [t for t in targets if not Path(t).is_dir()]
    return info


# -- on the client ------------------------------------------------------------------------------
class DaskPool:
    """Submits runs to a Dask cluster; same ``run``/``close`` interface as the local pool."""

    def __init__(self, address: str, targets: Sequence[str]) -> None:
        kind, value = parse_cluster(address)
        try:
            # Through Any: Dask is optional, and its typing varies between versions.
            distributed: Any = importlib.import_module("distributed")
        except ImportError as exc:
            raise ClusterError(f"--cluster needs Dask distributed: {_INSTALL}") from exc
        self.address = address
        self.cluster: Any = None
        if kind == "local":
            self.cluster = distributed.LocalCluster(
                n_workers=int(value),
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                # No dashboard, and the scheduler's HTTP endpoint on a free port, not on
                # 8787 where another cluster may already listen.
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                host="127.0.0.1",
            )
            scheduler = self.cluster.scheduler_address
        else:
            scheduler = str(value)
        try:
            self.client: Any = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT)
        except OSError as exc:
            self._close_cluster()
            raise ClusterError(
                f"--cluster {address}: cannot reach a Dask scheduler there ({exc}); start one "
                "with `dask scheduler` and workers with `dask worker tcp://HOST:PORT`"
            ) from exc
        try:
            self.workers = self._check(targets)
        except BaseException:
            self.close()
            raise

    def _check(self, targets: Sequence[str]) -> dict[str, dict[str, Any]]:
        try:
            self.client.wait_for_workers(1, timeout=60)
        except TimeoutError as exc:
            raise ClusterError(
                f"--cluster {self.address}: the scheduler has no worker after 60 s; start "
                f"some with `dask worker {self.client.scheduler.address}`"
            ) from exc
        try:
            infos: dict[str, dict[str, Any]] = self.client.run(worker_check, list(targets))
        except Exception as exc:
            raise ClusterError(
                f"--cluster {self.address}: a worker cannot run plan_bridge ({exc}); install "
                f"this smach-planner version on every worker ({_INSTALL})"
            ) from exc
        lacking = {a: i["missing"] for a, i in infos.items() if i["missing"]}
        if lacking:
            raise ClusterError(
                f"--cluster {self.address}: workers lack the domain folders "
                + "; ".join(f"{a}: {', '.join(m)}" for a, m in sorted(lacking.items()))
                + " (each worker needs them at the same absolute path)"
            )
        return infos

    def run(
        self,
        specs: list[RunSpec],
        run_timeout: float,
        on_result: Callable[[RunSpec, dict[str, Any]], None],
    ) -> None:
        as_completed: Any = importlib.import_module("distributed").as_completed
        futures: dict[Any, RunSpec] = {}
        for spec in specs:
            # Workers get absolute paths; the row's target is the folder's name either way.
            remote = dataclasses.replace(spec, target=str(Path(spec.target).resolve()))
            futures[self.client.submit(run_task, remote, run_timeout, pure=False)] = spec
        for future in as_completed(list(futures)):
            spec = futures[future]
            try:
                row: dict[str, Any] = future.result()
            except Exception as exc:
                # KilledWorker: the run took down every worker it was tried on.
                row = failure_row(spec, "crashed", f"{type(exc).__name__}: {exc}"[:300], 0.0)
            if row["outcome"] == "timeout" and row.get("worker"):
                self._restart(str(row["worker"]))
            on_result(spec, row)

    def _restart(self, worker: str) -> None:
        """Restart a worker whose run overran (its thread is still stuck in there)."""
        try:
            self.client.restart_workers([worker], timeout=60, raise_for_error=False)
        except Exception:
            # A worker without a nanny cannot be restarted; its stuck thread only costs
            # that worker's slot, the other runs go on elsewhere.
            return

    def close(self) -> None:
        try:
            self.client.close()
        finally:
            self._close_cluster()

    def _close_cluster(self) -> None:
        if self.cluster is not None:
            self.cluster.close()
            self.cluster = None
