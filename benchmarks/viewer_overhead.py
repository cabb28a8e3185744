"""What watching costs: the core benchmark's chain with a journal and a live viewer.

Usage::

    .venv/bin/python benchmarks/viewer_overhead.py            # about 30 s
    .venv/bin/python benchmarks/viewer_overhead.py --quick

Scenario: the ``chain`` of benchmarks/core_bench.py (a 1000-state StateMachine of
trivial states), us/transition, best of interleaved trials; then the same chain
whose states each do ``--work`` microseconds of busy work (a state that does
something). Configurations:

* ``bare``            nobody listens
* ``listener``        one no-op listener: the cost of the core building and
                      delivering the events (three per transition), paid by any watcher
* ``viewer``          ``smach.introspection.serve`` with a browser-like client reading
                      the server-sent events stream
* ``journal``         ``Journal`` writing JSON lines, flushed per event
* ``journal+viewer``  both

The ratios printed are against ``bare`` and against ``listener`` (what the viewer or
the journal add on top of the event stream itself).
"""

from __future__ import annotations

import argparse
import gc
import os
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from typing import Any

import smach
from smach.introspection import serve
from smach.introspection.journal import Journal


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


class Reader(threading.Thread):
    """A client of the viewer's SSE stream that reads everything (like a browser)."""

    def __init__(self, host: str, port: int) -> None:
        super().__init__(daemon=True)
        self.sock = socket.create_connection((host, port))
        self.sock.sendall(f"GET /api/stream HTTP/1.1\r\nHost: {host}:{port}\r\n\r\n".encode())
        self.bytes = 0
        self.messages = 0

    def run(self) -> None:
        try:
            while chunk := self.sock.recv(1 << 16):
                self.bytes += len(chunk)
                self.messages += chunk.count(b"event: update")
        except OSError:
            pass

    def close(self) -> None:
        self.sock.close()


def setup(kind: str, sm: smach.StateMachine, tmp: str) -> Callable[[], None]:
    """Attach the watchers of ``kind``; return how to detach them."""
    closers: list[Callable[[], None]] = []
    if kind == "listener":
        noop = lambda event: None  # noqa: E731
        sm.add_listener(noop)
        closers.append(lambda: sm.remove_listener(noop))
    if "journal" in kind:
        journal = Journal(os.path.join(tmp, f"{kind}.jsonl"), sm)
        closers.append(journal.close)
    if "viewer" in kind:
        viewer = serve(sm, quiet=True)
        reader = Reader(viewer.host, viewer.port)
        reader.start()
        deadline = time.monotonic() + 5
        while viewer.clients < 1 and time.monotonic() < deadline:
            time.sleep(0.01)

        def close() -> None:
            reader.close()
            viewer.close()

        closers.append(close)
    return lambda: [c() for c in reversed(closers)] and None


def measure(kinds: list[str], n: int, work_us: float, trials: int) -> dict[str, float]:
    """Best us/transition per kind; trials interleaved so machine drift hits all alike."""
    samples: dict[str, list[float]] = {k: [] for k in kinds}
    with tempfile.TemporaryDirectory() as tmp:
        machines = {k: chain(n, work_us) for k in kinds}
        detach = {k: setup(k, machines[k], tmp) for k in kinds}
        for sm in machines.values():
            sm.execute()  # warm up (compiles the slot table)
        for _ in range(trials):
            for kind in kinds:
                gc.collect()
                gc.disable()
                started = time.perf_counter()
                machines[kind].execute()
                elapsed = time.perf_counter() - started
                gc.enable()
                samples[kind].append(elapsed / n * 1e6)
                if "viewer" in kind:
                    time.sleep(0.05)  # let the viewer catch up between trials, as in use
        for d in detach.values():
            d()
    # The minimum: on a shared machine, the least disturbed trial (as timeit advises).
    return {k: min(v) for k, v in samples.items()}


def report(title: str, result: dict[str, float]) -> None:
    bare = result["bare"]
    floor = result["listener"]
    print(f"\n{title}")
    print(f"{'configuration':<16} {'us/transition':>14} {'x bare':>8} {'x listener':>11}")
    for kind, value in result.items():
        print(f"{kind:<16} {value:>14.2f} {value / bare:>8.2f} {value / floor:>11.2f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--work", type=float, default=100.0, help="us of work per state")
    args = parser.parse_args(argv)
    n = 1000
    trials = 5 if args.quick else 15
    kinds = ["bare", "listener", "viewer", "journal", "journal+viewer"]
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cpus, chain of {n}, {trials} trials")
    trivial = measure(kinds, n, 0.0, trials)
    report("trivial states (the core benchmark's chain)", trivial)
    working = measure(kinds, n, args.work, max(3, trials // 3))
    report(f"states doing {args.work:g} us of work", working)
    viewer_on_floor = trivial["viewer"] / trivial["listener"]
    print(
        f"\nviewer on top of the event stream: {100 * (viewer_on_floor - 1):+.1f}% (trivial states); "
        f"journal+viewer with {args.work:g} us states: "
        f"{100 * (working['journal+viewer'] / working['bare'] - 1):+.1f}% vs bare"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
