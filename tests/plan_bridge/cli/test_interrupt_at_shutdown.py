"""Ctrl-C while `plan-bridge run` shuts down, after its report (the planner workers
stop at exit): the process ends at once, quietly, with 130; it printed a
`KeyboardInterrupt` traceback from `subprocess.wait` in the pool's atexit hook."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.planning.worker import WorkerPool
from waiting import wait_until

ROOT = Path(__file__).parents[3]


def _interrupt_until_exit(process: subprocess.Popen[str], every: float = 0.02) -> str:
    """Press Ctrl-C every ``every`` seconds until ``process`` exits; its remaining stderr."""
    deadline = time.monotonic() + 30
    while process.poll() is None and time.monotonic() < deadline:
        process.send_signal(signal.SIGINT)
        time.sleep(every)
    assert process.stderr is not None
    return process.stderr.read()


@pytest.mark.timeout(120)
def test_ctrl_c_while_run_shuts_down_after_its_report_exits_quietly_with_130() -> None:
    with subprocess.Popen(
        [sys.executable, "-m", "plan_bridge", "run", str(ROOT / "domains" / "fetch_drink")],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    ) as process:
        assert process.stderr is not None
        for line in process.stderr:
            if line.startswith("  time: "):  # the summary's last line: the report is out
                break
        else:
            pytest.fail("the run printed no summary")
        rest = _interrupt_until_exit(process)
    assert process.returncode in (130, -signal.SIGINT), rest  # -2: after Python's own shutdown
    assert "Traceback" not in rest and "Exception ignored" not in rest, rest


CHILD = textwrap.dedent(
    """
    import sys, time
    from plan_bridge.planning import worker

    pool = worker.default_pool()
    pool.warm_up(1)
    pool._idle[0].wait_ready()
    print(pool._idle[0].pid, flush=True)
    close = worker.Worker.close

    def slow_close(self):  # a worker that takes its time to exit
        print("closing", flush=True)
        time.sleep(60)
        close(self)

    worker.Worker.close = slow_close
    """
)


@pytest.mark.timeout(120)
def test_ctrl_c_while_the_planner_workers_stop_at_exit_ends_quietly_with_130() -> None:
    with subprocess.Popen(
        [sys.executable, "-c", CHILD],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    ) as process:
        assert process.stdout is not None
        pid = int(process.stdout.readline())
        assert process.stdout.readline() == "closing\n"  # in the atexit hook, waiting
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=30)
    assert process.returncode == 130, err
    assert err == ""  # no traceback
    # The worker was killed (SIGKILL is delivered when the kernel gets to it: wait).
    assert wait_until(lambda: not Path(f"/proc/{pid}").exists() or _zombie(pid))


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1].startswith("Z")
    except OSError:
        return True


class FakeWorker:
    def __init__(self, interrupt: bool = False) -> None:
        self.interrupt = interrupt
        self.closed = self.killed = False

    def is_ready(self) -> bool:
        return True

    def close(self) -> None:
        if self.interrupt:
            raise KeyboardInterrupt
        self.closed = True

    def kill(self) -> None:
        self.killed = True


def test_a_ctrl_c_while_the_pool_closes_kills_the_workers_not_stopped_yet() -> None:
    pool = WorkerPool(max_workers=3)
    workers = [FakeWorker(), FakeWorker(interrupt=True), FakeWorker()]
    fakes: list[Any] = list(workers)
    pool._idle, pool._count = fakes, 3
    with pytest.raises(KeyboardInterrupt):
        pool.close()
    assert workers[0].closed and not workers[0].killed
    assert workers[1].killed and workers[2].killed  # no waiting on them any more
    assert pool._idle == [] and os.getpid() == pool._pid
