"""Load and soak: long plans with a journal and a connected viewer, many executives at once.

    python benchmarks/load_soak.py [--steps 2000] [--executives 16] [--soak-seconds 600]

1. One executive runs a 2000-step plan (no-op symbolic skills) with the journal and a
   live viewer attached, a client (another process, like a browser) connected to the
   viewer's event stream: time until the run is over and its journal on disk, vs the
   same plan with nothing attached.
2. 16 executives run concurrently in one process (threads), each a 200-step plan.
3. Soak: rounds of (2) for --soak-seconds; prints memory (RSS) and time per round, and
   the growth between the first and the last quarter of the soak. Flat = no leak.

The plan is fixed (a stub planner returns it), so the figures measure the executive,
compiler, skills, journal and viewer, not Fast Downward.
"""

from __future__ import annotations

import argparse
import gc
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import FactLike, PlanningTask, load_task_from_text
from plan_bridge.planning.planner import PlanResult, PlanStatus, PlanStep
from smach.introspection.journal import Journal


def chain_task(n: int) -> PlanningTask:
    """A robot walks a line of n+1 cells: the plan is n moves."""
    cells = " ".join(f"c{i}" for i in range(n + 1))
    links = " ".join(f"(next c{i} c{i + 1})" for i in range(n))
    domain = """(define (domain line) (:requirements :strips :typing) (:types cell)
      (:predicates (at ?c - cell) (next ?a ?b - cell))
      (:action step :parameters (?a ?b - cell) :precondition (and (at ?a) (next ?a ?b))
        :effect (and (at ?b) (not (at ?a)))))"""
    problem = f"""(define (problem walk) (:domain line) (:objects {cells} - cell)
      (:init (at c0) {links}) (:goal (at c{n})))"""
    return load_task_from_text(domain, problem)


class FixedPlanner:
    """Returns the straight walk; a stand-in that makes planning cost nothing."""

    name = "fixed"

    def __init__(self, n: int) -> None:
        self.plan = [PlanStep("step", (f"c{i}", f"c{i + 1}")) for i in range(n)]

    def solve(self, task: PlanningTask, *, timeout: float, initial_state: Any = None) -> PlanResult:
        facts: set[FactLike] = set(initial_state or task.initial_facts)
        start = next(int(f[1][1:]) for f in facts if f[0] == "at")  # type: ignore[index]
        return PlanResult(PlanStatus.SOLVED, self.plan[start:], planner=self.name)


CLIENT = """
import sys, urllib.request
with urllib.request.urlopen(sys.argv[1], timeout=60) as stream:
    print("connected", flush=True)
    while stream.read(4096):
        pass
"""


def rss_mb() -> float:
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * resource.getpagesize() / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run_mission(
    task: PlanningTask, planner: FixedPlanner, *, journal: Path | None = None, viewer: bool = False
) -> tuple[float, str | None]:
    world = SimulatedWorld(task)
    ex = Executive(task, symbolic_skills(world), planner)  # type: ignore[arg-type]
    closers: list[Any] = []
    if journal is not None:
        closers.append(Journal(journal, ex))
    client = None
    if viewer:
        from smach.introspection import serve

        server = serve(ex, quiet=True)
        closers.append(server)
        # A connected browser: another process reading the event stream until killed.
        client = subprocess.Popen(
            [sys.executable, "-c", CLIENT, server.url.rstrip("/") + "/api/stream"],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert client.stdout is not None
        client.stdout.readline()  # connected
    started = time.perf_counter()
    outcome = ex.execute()
    if journal is not None and hasattr(closers[0], "flush"):
        closers[0].flush()  # every line on disk: part of the run's cost
    elapsed = time.perf_counter() - started
    if client is not None:
        client.kill()
        client.wait()
        assert client.stdout is not None
        client.stdout.close()
    for closer in closers:
        closer.close()
    return elapsed, outcome


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--executives", type=int, default=16)
    parser.add_argument("--steps-each", type=int, default=200)
    parser.add_argument("--soak-seconds", type=float, default=600.0)
    args = parser.parse_args()

    print(f"1. one executive, a {args.steps}-step plan", flush=True)
    task = chain_task(args.steps)
    planner = FixedPlanner(args.steps)
    bare = [run_mission(task, planner)[0] for _ in range(3)]
    with tempfile.TemporaryDirectory() as tmp:
        watched = []
        for i in range(3):
            elapsed, outcome = run_mission(
                task, planner, journal=Path(tmp) / f"run{i}.jsonl", viewer=True
            )
            assert outcome == "succeeded"
            watched.append(elapsed)
        size = (Path(tmp) / "run0.jsonl").stat().st_size
    b, w = statistics.median(bare), statistics.median(watched)
    print(
        f"   bare: {b:.3f} s ({b / args.steps * 1e6:.0f} us/step); journal + live viewer + client: "
        f"{w:.3f} s ({w / args.steps * 1e6:.0f} us/step, x{w / b:.2f}); journal {size / 2**20:.1f} MB",
        flush=True,
    )

    small = chain_task(args.steps_each)
    small_planner = FixedPlanner(args.steps_each)

    def round_of_executives() -> float:
        outcomes: list[str | None] = []
        threads = [
            threading.Thread(target=lambda: outcomes.append(run_mission(small, small_planner)[1]))
            for _ in range(args.executives)
        ]
        started = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert outcomes == ["succeeded"] * args.executives, outcomes
        return time.perf_counter() - started

    print(f"2. {args.executives} concurrent executives x {args.steps_each} steps", flush=True)
    first = round_of_executives()
    print(
        f"   {first:.3f} s per round ({first / (args.executives * args.steps_each) * 1e6:.0f} us/step overall)",
        flush=True,
    )

    print(f"3. soak for {args.soak_seconds:.0f} s", flush=True)
    samples: list[tuple[float, float, float]] = []
    start = time.monotonic()
    next_report = start
    while time.monotonic() - start < args.soak_seconds:
        seconds = round_of_executives()
        gc.collect()
        now = time.monotonic()
        samples.append((now - start, rss_mb(), seconds))
        if now >= next_report:
            print(
                f"   t={now - start:6.0f} s  rss {samples[-1][1]:7.1f} MB  round {seconds:.3f} s  threads {threading.active_count()}",
                flush=True,
            )
            next_report = now + max(30.0, args.soak_seconds / 20)
    quarter = max(1, len(samples) // 4)
    early, late = samples[:quarter], samples[-quarter:]
    grow = statistics.mean(s[1] for s in late) - statistics.mean(s[1] for s in early)
    slow = statistics.mean(s[2] for s in late) / statistics.mean(s[2] for s in early)
    print(
        f"   {len(samples)} rounds ({len(samples) * args.executives} missions, "
        f"{len(samples) * args.executives * args.steps_each} steps); RSS first quarter "
        f"{statistics.mean(s[1] for s in early):.1f} MB -> last quarter {statistics.mean(s[1] for s in late):.1f} MB "
        f"({grow:+.1f} MB); round time x{slow:.2f}",
        flush=True,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
