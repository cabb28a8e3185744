"""The study on a real Dask cluster: scheduler and workers as processes on loopback."""

from __future__ import annotations

import csv
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from plan_bridge.study import RunSpec, run_study
from plan_bridge.study.cluster import ClusterError, parse_cluster
from plan_bridge.study.runs import FIELDS, VARYING_FIELDS

ROOMS = str(Path(__file__).parents[1] / "data" / "rooms")
DASK = Path(sys.executable).with_name("dask")


def specs(seeds: range) -> list[RunSpec]:
    return [
        RunSpec(ROOMS, a, r, s) for a in ("planned", "no-replan") for r in (0.0, 0.5) for s in seeds
    ]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


class Cluster:
    """A `dask scheduler` and `dask worker` processes started by the test, each in its own group."""

    def __init__(self) -> None:
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.processes: list[subprocess.Popen[bytes]] = []
        self.workers: dict[str, subprocess.Popen[bytes]] = {}
        self._start(
            [
                str(DASK),
                "scheduler",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
                "--port",
                str(self.port),
            ]
        )
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=1).close()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise RuntimeError("the dask scheduler did not start") from None
                time.sleep(0.1)

    def _start(self, command: list[str]) -> subprocess.Popen[bytes]:
        process = subprocess.Popen(
            command,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        self.processes.append(process)
        return process

    def add_worker(self, name: str) -> None:
        self.workers[name] = self._start(
            [
                str(DASK),
                "worker",
                self.address,
                "--name",
                name,
                "--nthreads",
                "1",
                "--nworkers",
                "1",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
            ]
        )

    def wait_for_workers(self, count: int) -> dict[str, str]:
        """Names -> addresses of the connected workers, once there are ``count``."""
        from distributed import Client

        with Client(self.address, timeout=30) as client:
            client.wait_for_workers(count, timeout=60)
            info = client.scheduler_info()["workers"]
            return {w["name"]: address for address, w in info.items()}

    def kill(self, name: str) -> None:
        """SIGKILL a worker and its nanny: the scheduler sees the connection drop."""
        os.killpg(self.workers[name].pid, signal.SIGKILL)
        self.workers[name].wait(10)

    def close(self) -> None:
        for process in reversed(self.processes):
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGTERM)
        for process in self.processes:
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(10)


@pytest.fixture
def cluster() -> Iterator[Cluster]:
    pytest.importorskip("distributed")
    started = Cluster()
    try:
        started.add_worker("a")
        started.add_worker("b")
        started.wait_for_workers(2)
        yield started
    finally:
        started.close()


def without_varying(rows: list[dict[str, str]]) -> dict[tuple[str, ...], dict[str, str]]:
    return {
        (r["approach"], r["fault_rate"], r["seed"]): {
            k: v for k, v in r.items() if k not in VARYING_FIELDS
        }
        for r in rows
    }


@pytest.mark.timeout(180)
def test_cluster_rows_equal_local_rows_except_timing_and_placement(
    cluster: Cluster, tmp_path: Path
) -> None:
    local = run_study(specs(range(2)), tmp_path / "local", jobs=2)
    remote = run_study(specs(range(2)), tmp_path / "cluster", cluster=cluster.address)
    assert len(remote) == 8
    assert without_varying(remote) == without_varying(local)
    addresses = set(cluster.wait_for_workers(2).values())
    assert {r["worker"] for r in remote} <= addresses
    assert all(r["worker"].startswith("local pid ") for r in local)
    sessions = (tmp_path / "cluster" / "environment.json").read_text()
    assert cluster.address in sessions and "cpu_model" in sessions


@pytest.mark.timeout(180)
def test_a_worker_killed_mid_study_loses_no_run_and_resume_writes_none_twice(
    cluster: Cluster, tmp_path: Path
) -> None:
    addresses = cluster.wait_for_workers(2)
    name_of = {address: name for name, address in addresses.items()}
    killed: list[str] = []
    after_kill: list[str] = []

    def progress(done: int, total: int, spec: RunSpec, row: dict[str, str], e: float) -> None:
        if not killed:
            # The worker that just finished a run has already started its next one.
            killed.append(name_of[row["worker"]])
            cluster.kill(killed[0])
        else:
            after_kill.append(row["worker"])

    out = tmp_path / "study"
    rows = run_study(specs(range(4)), out, cluster=cluster.address, progress=progress)
    assert len(rows) == 16
    assert {r["outcome"] for r in rows} <= {"succeeded", "aborted"}, [r["error"] for r in rows]
    survivor = addresses[({"a", "b"} - set(killed)).pop()]
    assert after_kill and survivor in after_kill
    with (out / "results.csv").open() as f:
        written = [(r["approach"], r["fault_rate"], r["seed"]) for r in csv.DictReader(f)]
    assert len(written) == len(set(written)) == 16
    # Resuming with more seeds runs only the new ones, on the surviving worker.
    calls: list[RunSpec] = []
    rows = run_study(
        specs(range(5)),
        out,
        cluster=cluster.address,
        progress=lambda d, t, s, r, e: calls.append(s),
    )
    assert len(rows) == 20 and {c.seed for c in calls} == {4} and len(calls) == 4
    with (out / "results.csv").open() as f:
        header = next(csv.reader(f))
        assert header == FIELDS
        assert sum(1 for _ in f) == 20


def test_cluster_addresses_are_checked_before_anything_starts() -> None:
    assert parse_cluster("local:4") == ("local", 4)
    assert parse_cluster("tcp://10.0.0.5:8786") == ("tcp", "tcp://10.0.0.5:8786")
    for bad in ("local:0", "local:x", "10.0.0.5:8786", "tcp://host", "http://h:1"):
        with pytest.raises(ClusterError, match=r"tcp://HOST:PORT|local:N"):
            parse_cluster(bad)


@pytest.mark.timeout(60)
def test_an_unreachable_scheduler_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr("plan_bridge.study.cluster.CONNECT_TIMEOUT", 2.0)
    with pytest.raises(ClusterError, match="cannot reach a Dask scheduler"):
        run_study(specs(range(1)), tmp_path, cluster=f"tcp://127.0.0.1:{free_port()}")


SLEEPY = str(Path(__file__).parents[1] / "data" / "sleepy")


@pytest.mark.timeout(180)
def test_a_run_that_hangs_on_a_worker_is_recorded_as_timeout_and_the_others_finish(
    cluster: Cluster, tmp_path: Path
) -> None:
    hangs = RunSpec(SLEEPY, "planned", 1.0, 0)
    others = [RunSpec(SLEEPY, "planned", 0.0, s) for s in range(3)]
    rows = run_study([hangs, *others], tmp_path, cluster=cluster.address, run_timeout=15.0)
    outcome = {r["seed"] + "@" + r["fault_rate"]: r["outcome"] for r in rows}
    assert outcome == {"0@1": "timeout", "0@0": "succeeded", "1@0": "succeeded", "2@0": "succeeded"}
    assert "exceeded 15 s" in next(r["error"] for r in rows if r["outcome"] == "timeout")
    # The worker with the stuck thread was restarted by its nanny: a new worker process
    # (new address) took its place.
    stuck = next(r["worker"] for r in rows if r["outcome"] == "timeout")
    assert stuck not in cluster.wait_for_workers(2).values()


@pytest.mark.timeout(180)
def test_each_cluster_row_records_its_worker_host_and_cpu_and_the_report_names_the_machines(
    cluster: Cluster, tmp_path: Path
) -> None:
    from plan_bridge.study import write_report
    from plan_bridge.study.environment import cpu_model

    rows = run_study(specs(range(1)), tmp_path, cluster=cluster.address)
    assert len(rows) == 4
    # The workers run on this machine: its host name and CPU model, row by row.
    assert {(r["host"], r["cpu_model"]) for r in rows} == {(socket.gethostname(), cpu_model())}
    text = write_report(rows, tmp_path, [], "plan-bridge study rooms --cluster").read_text()
    assert (
        f"- Runs per machine (host, CPU model: runs): `{socket.gethostname()}` ({cpu_model()}): 4."
        in text
    )
