"""What watching costs: the core benchmark's chain with a journal and a live viewer.

Usage::

    .venv/bin/python benchmarks/viewer_overhead.py            # about a minute
    .venv/bin/python benchmarks/viewer_overhead.py --quick
    .venv/bin/python benchmarks/viewer_overhead.py --work 0,10,100

Scenario: the ``chain`` of benchmarks/core_bench.py (a 1000-state StateMachine),
us/transition, first with trivial states (``--work 0``, about 0.3 us per
transition), then with states that each do ``--work`` microseconds of busy work
(states that do something). Configurations:

* ``bare``            nobody listens
* ``listener``        one no-op ordinary listener: every transition builds and
                      delivers three Event objects
* ``viewer``          ``smach.introspection.serve`` with a browser-like client (another
                      process) reading the server-sent events stream
* ``journal``         ``Journal`` writing JSON lines (background writer, batched)
* ``journal+viewer``  both

A trial runs the chain several times back to back (so the journal's writer and
the viewer's pump work while the machine runs, as in a long mission) and, for the
journal, includes the final ``flush()``: the time is what the run costs until every
line is on disk. Between trials every watcher is let to settle (untimed), so no
configuration pays for another one's backlog. Trials are interleaved so machine
drift hits all configurations alike, and a trial during which the hypervisor stole
CPU time (Linux ``/proc/stat``) is run again; the table gives the median and the
best trial, the ratios are of medians.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import smach
from smach.introspection import serve
from smach.introspection.journal import Journal

KINDS = ["bare", "listener", "viewer", "journal", "journal+viewer"]


class Trivial(smach.State):
    def __init__(self, work_us: float = 0.0) -> None:
        super().__init__(outcomes=["done"])
        self.work_s = work_us / 1e6

    def execute(self, ud: Any) -> str:
        if self.work_s:
            end = time.perf_counter() + self.work_s
            while time.perf_counter() < end:
                pass
        return "done"


def chain(n: int, work_us: float) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["finished"])
    with sm:
        for i in range(n):
            target = f"S{i + 1}" if i + 1 < n else "finished"
            smach.StateMachine.add(f"S{i}", Trivial(work_us), transitions={"done": target})
    return sm


READER = r"""
import socket, sys
host, port = sys.argv[1], int(sys.argv[2])
sock = socket.create_connection((host, port))
sock.sendall(f"GET /api/stream HTTP/1.1\r\nHost: {host}:{port}\r\n\r\n".encode())
print("connected", flush=True)
while sock.recv(1 << 16):
    pass
"""


class Reader:
    """A client of the viewer's SSE stream that reads everything, in its own process
    (like a browser: its work does not compete for this interpreter's lock)."""

    def __init__(self, host: str, port: int) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-c", READER, host, str(port)],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.process.stdout is not None
        self.process.stdout.readline()  # connected

    def close(self) -> None:
        self.process.kill()
        self.process.wait()
        if self.process.stdout is not None:
            self.process.stdout.close()


@dataclass
class Watchers:
    """What is attached to one machine, and how to finish and settle a trial."""

    finish: list[Callable[[], None]] = field(default_factory=list)  # timed (journal flush)
    settle: list[Callable[[], None]] = field(default_factory=list)  # untimed
    close: list[Callable[[], None]] = field(default_factory=list)


def setup(kind: str, sm: smach.StateMachine, tmp: str) -> Watchers:
    """Attach the watchers of ``kind``."""
    w = Watchers()
    if kind == "listener":
        noop = lambda event: None  # noqa: E731
        sm.add_listener(noop)
        w.close.append(lambda: sm.remove_listener(noop))
    if "journal" in kind:
        journal = Journal(os.path.join(tmp, f"{kind}.jsonl"), sm)
        flush = getattr(journal, "flush", None)  # journals that flush per event: nothing
        if flush is not None:
            w.finish.append(flush)
        w.close.append(journal.close)
    if "viewer" in kind:
        viewer = serve(sm, quiet=True)
        reader = Reader(viewer.host, viewer.port)
        deadline = time.monotonic() + 5
        while viewer.clients < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        source: Any = viewer.source

        def settle() -> None:
            # Let the pump take what the run left, and its throttle sleep run out.
            deadline = time.monotonic() + 5
            while source._pending and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(2 * viewer.interval)

        def close() -> None:
            reader.close()
            viewer.close()

        w.settle.append(settle)
        w.close.append(close)
    return w


def steal() -> int:
    """CPU time the hypervisor took from this machine so far (ticks; 0 if unknown)."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()
        return int(fields[8]) if fields[0] == "cpu" and len(fields) > 8 else 0
    except OSError:
        return 0


def measure(n: int, work_us: float, trials: int, reps: int) -> dict[str, list[float]]:
    """us/transition of every trial, per configuration.

    A trial during which the hypervisor took CPU time (steal time, on a virtual
    machine) is run again, up to three times; the least disturbed one counts.
    """
    samples: dict[str, list[float]] = {k: [] for k in KINDS}
    with tempfile.TemporaryDirectory() as tmp:
        machines = {k: chain(n, work_us) for k in KINDS}
        watchers = {k: setup(k, machines[k], tmp) for k in KINDS}
        for kind, sm in machines.items():
            sm.execute()  # warm up (compiles the slot table)
            for settle in watchers[kind].settle:
                settle()
        for _ in range(trials):
            for kind in KINDS:
                sm = machines[kind]
                attempts: list[tuple[int, float]] = []
                for _ in range(4):
                    gc.collect()
                    gc.disable()
                    stolen = steal()
                    started = time.perf_counter()
                    for _ in range(reps):
                        sm.execute()
                    for finish in watchers[kind].finish:
                        finish()
                    elapsed = time.perf_counter() - started
                    stolen = steal() - stolen
                    gc.enable()
                    attempts.append((stolen, elapsed / (n * reps) * 1e6))
                    for settle in watchers[kind].settle:
                        settle()
                    if stolen == 0:
                        break
                samples[kind].append(min(attempts)[1])
        for w in watchers.values():
            for close in reversed(w.close):
                close()
    return samples


def report(title: str, samples: dict[str, list[float]]) -> dict[str, float]:
    median = {k: statistics.median(v) for k, v in samples.items()}
    bare, floor = median["bare"], median["listener"]
    print(f"\n{title}")
    print(
        f"{'configuration':<16} {'us/transition':>14} {'best':>8} {'x bare':>8} "
        f"{'overhead':>9} {'x listener':>11}"
    )
    for kind, value in median.items():
        print(
            f"{kind:<16} {value:>14.2f} {min(samples[kind]):>8.2f} {value / bare:>8.2f} "
            f"{100 * (value / bare - 1):>+8.1f}% {value / floor:>11.2f}"
        )
    return median


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument(
        "--work", default="0,10,100", help="us of work per state, comma-separated (0: trivial)"
    )
    parser.add_argument("--trials", type=int, default=None)
    args = parser.parse_args(argv)
    n = 1000
    works = [float(w) for w in args.work.split(",")]
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cpus, chain of {n}")
    summary = []
    for work in works:
        # About 0.3 s of bare run per trial with working states (20 runs when trivial).
        reps = max(1, min(20, round(300_000 / (n * max(work, 5.0)))))
        trials = args.trials or (3 if args.quick else (9 if work < 50 else 5))
        title = (
            "trivial states (the core benchmark's chain)"
            if work == 0
            else f"states doing {work:g} us of work"
        )
        samples = measure(n, work, trials, reps)
        median = report(f"{title}: {trials} trials x {reps} runs", samples)
        summary.append((work, median))
    print("\njournal + connected viewer, median overhead vs bare:")
    for work, median in summary:
        print(
            f"  {work:>5g} us/state: {100 * (median['journal+viewer'] / median['bare'] - 1):+6.1f}%"
            f"  ({median['journal+viewer'] - median['bare']:.2f} us/transition)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
