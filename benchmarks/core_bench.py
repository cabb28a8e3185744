"""Benchmark of the smach core, with peers and floors measured in the same run.

Usage::

    .venv/bin/python benchmarks/core_bench.py            # full run, 6 fresh processes
    .venv/bin/python benchmarks/core_bench.py --quick    # small sizes, about a minute
    .venv/bin/python benchmarks/core_bench.py --processes 10 --only nested,nested_key
    .venv/bin/python benchmarks/core_bench.py --processes 1 --json results.json

Every scenario is timed in repeated trials; each trial runs the scenario enough times
to last at least ``min_trial_s`` (gc disabled inside the timed region, as ``timeit``
does), and the table reports the median, the minimum and the 90th percentile of the
per-unit cost over the trials. The trials of the throughput scenarios are interleaved
round-robin, and the ``calls`` column gives, per round, the scenario's sample divided by
the bare-function-call sample of the same round (median over rounds): on a shared
machine whose speed drifts, that ratio is the stable number. Preemption latency is one
sample per trial.

Scenarios (names as printed in the table):

* ``chain``             1000-state chain StateMachine of trivial states, us/transition
* ``remap_loop``        2-state loop, each state reads and writes a remapped key, us/transition
* ``concurrence``       Concurrence of 8 trivial children, us/execution
* ``concurrence_busy``  the same while a separate busy-loop process occupies a core
* ``iterator_small`` / ``iterator_medium`` / ``iterator_large``
                        Iterator over 1,000 / 10,000 / 100,000 items, us/item
* ``nested``            50 StateMachines nested in each other, one leaf, us/execution
* ``nested_key``        the same, each machine declaring ``x`` as input and output key and
                        the leaf adding 1 to it (the root is given a UserData holding
                        ``x``), us/execution
* ``nested_logged`` / ``nested_key_logged``
                        the same two with loggers installed (``smach.set_loggers`` with a
                        function that formats each line and drops it), us/execution
* ``preempt_event``     latency request_preempt() -> execute() returns, state waits on
                        ``self.preempt_event.wait()``, ms
* ``preempt_sleep``     the same, state in ``self.sleep(10)``, ms
* ``preempt_poll``      the same, state polls ``preempt_requested()`` every 1 ms, ms
* ``call_function`` / ``call_method``  a bare Python call (loop overhead subtracted), us
* ``handloop``          a hand-written minimal transition loop (the pure-Python floor of
                        ``chain``: execute() + one dict lookup + one class check), us
* ``peer_py_trees``     py_trees Sequence(memory=True) of 1000 Success behaviours,
                        ticked once at the root, us/behaviour
* ``peer_transitions``  ``transitions.Machine`` toggled 10,000 times, us/change

Fresh processes (issue 39): one process's figure can be that process's luck (where
its stack, its objects or its code happened to land), so by default the measurement
runs in 6 fresh processes one after the other (``--processes N``; ``--processes 1``
measures in this process and prints the full single-run report) and the report gives,
for each scenario, the median of each process, the best and the worst process and
the spread (worst / best - 1); against the original, the ratio of every cell in every
process, the aims judged on the lowest (see core_spread.py). ``--only NAMES`` keeps
the named scenarios (a name also keeps its ``_logged`` variant) and the bare-call
floor; ``--cpu-time`` times the single-threaded scenarios in the thread's CPU time.
``--stack-sweep`` runs the nesting scenarios (and a 200-state chain, a flat loop, for
reference) from callers 0 to 160 frames deeper, in one process, with the page faults of
an execution at each depth: where a run's speed depends on where it is called from,
that table shows it.

With ``--original DIR`` (a checkout of ros/executive_smach) or ``--original-git URL``
(cloned into a temporary directory in this run), the original core is measured in the
same run, in three logging configurations, repeated and first execution: see
core_compare.py. Without it, the original's figures are the constants below (medians
measured earlier on the same machine).

(Over 600 lines: one benchmark's scenarios, floors, peers and report read best together.)
"""

from __future__ import annotations

import argparse
import gc
import json
import logging
import math
import multiprocessing
import os
import platform
import random
import resource
import sys
import tempfile
import threading
import time
import timeit
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import core_compare
import core_spread

import smach

# -- reference figures of the original SMACH core (measured earlier on this machine) ------------
# Medians, same scenarios and sizes as below. Not measured by this script.
ORIGINAL: dict[str, float | tuple[float, float]] = {
    "chain": 2.5,  # us/transition, 1000-state chain
    "remap_loop": 3.8,  # us/transition, remapped 2-state loop
    "concurrence": 300.0,  # us/execution, 8 trivial children
    "concurrence_busy": (4000.0, 16000.0),  # us/execution, range seen with the other core busy
    "iterator_medium": 410.0,  # us/item at 10,000 items (grows with the item count: quadratic)
    "nested": 210.0,  # us/execution, 50 nested StateMachines
    # preemption: bounded by the poll period of the state (no event to wait on)
}

# call_function median on the same machine when idle (ns); only used to print how much
# slower the machine was during a run (shared/virtual machines vary by 2x over seconds).
QUIET_CALL_NS = 22.5

# Targets for this implementation.
SPEEDUP_TARGETS = {"chain": 4.0, "remap_loop": 4.0, "nested": 4.0, "concurrence": 10.0}
ITERATOR_MAX_US = 2.0
ITERATOR_LINEARITY = 1.5  # us/item of the largest run <= 1.5x that of the smallest
PREEMPT_EVENT_MAX_MS = 0.2

SCENARIOS = (
    "chain",
    "remap_loop",
    "concurrence",
    "concurrence_busy",
    "iterator_small",
    "iterator_medium",
    "iterator_large",
    "nested",
    "nested_key",
    "nested_logged",
    "nested_key_logged",
    "preempt_event",
    "preempt_sleep",
    "preempt_poll",
    "call_function",
    "call_method",
    "handloop",
    "peer_py_trees",
    "peer_transitions",
)


def progress(msg: str) -> None:
    print(f"[core_bench] {msg}", file=sys.stderr, flush=True)


# -- statistics ---------------------------------------------------------------------------------
@dataclass
class Result:
    name: str
    what: str
    size: int
    unit: str
    samples: list[float] = field(repr=False)
    median: float = 0.0
    min: float = 0.0
    p90: float = 0.0
    calls: float | None = None  # median over rounds of (sample / call_function sample)

    def __post_init__(self) -> None:
        s = sorted(self.samples)
        n = len(s)
        self.median = s[n // 2] if n % 2 else (s[n // 2 - 1] + s[n // 2]) / 2
        self.min = s[0]
        self.p90 = s[max(0, math.ceil(0.9 * n) - 1)]  # nearest rank


@dataclass
class Config:
    quick: bool
    trials: int  # timed trials per throughput scenario
    min_trial_s: float  # minimum duration of one trial
    chain: int
    loop: int
    concurrence_children: int
    iterator_sizes: tuple[int, int, int]
    nesting: int
    preempt_trials: int
    peer_py_trees: int
    peer_transitions: int
    compare_trials: int  # rounds per logging configuration against the original
    only: tuple[str, ...] = ()  # --only: just these same-run comparison scenarios
    cpu_time: bool = False  # --cpu-time: the comparison's single-threaded trials in CPU time


FULL = Config(
    quick=False,
    trials=21,
    min_trial_s=0.05,
    chain=1000,
    loop=10_000,
    concurrence_children=8,
    iterator_sizes=(1_000, 10_000, 100_000),
    nesting=50,
    preempt_trials=200,
    peer_py_trees=1000,
    peer_transitions=10_000,
    compare_trials=9,
)
QUICK = Config(
    quick=True,
    trials=3,
    min_trial_s=0.005,
    chain=200,
    loop=1_000,
    concurrence_children=8,
    iterator_sizes=(100, 1_000, 10_000),
    nesting=50,
    preempt_trials=15,
    peer_py_trees=200,
    peer_transitions=1_000,
    compare_trials=3,
)


class Bench:
    """A throughput scenario: ``fn()`` does ``units`` units of work; samples are us/unit.

    Trials of all the scenarios of a run are interleaved (see :func:`run_interleaved`) so
    that a slow phase of the machine (CPU frequency, other processes) hits them alike.
    """

    #: The clock of a trial: wall time, or (``--cpu-time``, single-threaded scenarios of
    #: the comparison) the running thread's CPU time, which time spent descheduled by
    #: other processes on a loaded machine does not count.
    clock: Callable[[], int] = staticmethod(time.perf_counter_ns)

    def __init__(self, name: str, what: str, fn: Callable[[], object], units: int) -> None:
        self.name = name
        self.what = what
        self.fn = fn
        self.units = units
        self.reps = 1
        self.samples: list[float] = []

    def prepare(self, cfg: Config) -> None:
        """Warm up (compiles container tables, starts pool threads) and size a trial."""
        self.fn()
        t0 = time.perf_counter()
        self.fn()
        once = max(time.perf_counter() - t0, 1e-7)
        self.reps = max(1, math.ceil(cfg.min_trial_s / once))

    def trial(self) -> float:
        fn = self.fn
        gc.collect()
        gc.disable()
        clock = self.clock
        try:
            start = clock()
            for _ in range(self.reps):
                fn()
            elapsed = clock() - start
        finally:
            gc.enable()
        return elapsed / 1000.0 / (self.reps * self.units)


class CallBench(Bench):
    """The cost of one statement, minus the cost of the same loop running ``pass``."""

    def __init__(self, name: str, what: str, stmt: str, cpu_time: bool = False) -> None:
        super().__init__(name, what, lambda: None, 1)
        env = {"f": _f, "o": _Obj()}
        timer = time.thread_time if cpu_time else time.perf_counter
        self.stmt = timeit.Timer(stmt, timer=timer, globals=env)
        self.empty = timeit.Timer("pass", timer=timer, globals=env)

    def prepare(self, cfg: Config) -> None:
        number = 10_000
        once = max(self.stmt.timeit(number), 1e-7)
        self.reps = max(number, math.ceil(number * cfg.min_trial_s / once))

    def trial(self) -> float:  # timeit disables gc itself
        t = self.stmt.timeit(self.reps)
        e = self.empty.timeit(self.reps)
        return max(t - e, 0.0) / self.reps * 1e6


def run_interleaved(benches: list[Bench], cfg: Config) -> dict[str, Result]:
    """Round-robin: each round runs one trial of every scenario (rotating the order)."""
    for bench in benches:
        bench.prepare(cfg)
    for i in range(cfg.trials):
        k = i % len(benches)
        for bench in benches[k:] + benches[:k]:
            bench.samples.append(bench.trial())
        progress(f"round {i + 1}/{cfg.trials} of {len(benches)} scenario(s)")
    floor = next((b for b in benches if b.name == "call_function"), None)
    results = {}
    for bench in benches:
        res = Result(bench.name, bench.what, bench.units, "us", bench.samples)
        if floor is not None:
            # Per round: this scenario's sample over the function-call sample of the same
            # round; robust to the machine speeding up or slowing down during the run.
            # (A floor sample of 0: the call was lost in the noise of a loaded machine.)
            pairs = zip(bench.samples, floor.samples, strict=True)
            ratios = [a / b for a, b in pairs if b > 0]
            res.calls = Result("", "", 0, "", ratios).median if ratios else None
        results[bench.name] = res
        progress(
            f"{bench.name}: median {res.median:.4g} us ({cfg.trials} trials x {bench.reps} reps)"
        )
    return results


# -- states -------------------------------------------------------------------------------------
class Trivial(smach.State):
    def __init__(self, outcome: str = "done") -> None:
        super().__init__(outcomes=[outcome])
        self.outcome = outcome

    def execute(self, ud: Any) -> str:
        return self.outcome


class Copy(smach.State):
    """Reads ``inp``, writes ``inp + 1`` to ``out``; stops the loop at ``limit``."""

    def __init__(self, limit: int | None) -> None:
        super().__init__(outcomes=["next", "done"], input_keys=["inp"], output_keys=["out"])
        self.limit = limit

    def execute(self, ud: Any) -> str:
        value = ud.inp + 1
        ud.out = value
        if self.limit is not None and value >= self.limit:
            return "done"
        return "next"


class Bump(smach.State):
    """Adds 1 to ``x`` (declared as input and output key)."""

    def __init__(self) -> None:
        super().__init__(outcomes=["done"], input_keys=["x"], output_keys=["x"])

    def execute(self, ud: Any) -> str:
        ud.x = ud.x + 1
        return "done"


class ReadItem(smach.State):
    def __init__(self) -> None:
        super().__init__(outcomes=["continue"], input_keys=["it_data"])

    def execute(self, ud: Any) -> str:
        ud.it_data  # noqa: B018 - the read is the work
        return "continue"


# -- scenarios: smach ---------------------------------------------------------------------------
def bench_chain(cfg: Config) -> Bench:
    n = cfg.chain
    sm = smach.StateMachine(outcomes=["finished"])
    with sm:
        for i in range(n):
            target = f"S{i + 1}" if i + 1 < n else "finished"
            smach.StateMachine.add(f"S{i}", Trivial(), transitions={"done": target})

    def run() -> None:
        assert sm.execute() == "finished"

    return Bench("chain", f"{n}-state chain StateMachine", run, n)


def bench_remap_loop(cfg: Config) -> Bench:
    n = cfg.loop
    sm = smach.StateMachine(outcomes=["finished"])
    with sm:
        smach.StateMachine.add(
            "A",
            Copy(None),
            transitions={"next": "B", "done": "finished"},
            remapping={"inp": "x", "out": "y"},
        )
        smach.StateMachine.add(
            "B",
            Copy(n),
            transitions={"next": "A", "done": "finished"},
            remapping={"inp": "y", "out": "x"},
        )
    data = sm.userdata

    def run() -> None:
        data.x = 0
        assert sm.execute() == "finished"
        assert data.x == n  # every transition did its read and its write

    return Bench("remap_loop", f"2-state remapped loop, {n} transitions", run, n)


def make_concurrence(cfg: Config) -> smach.Concurrence:
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
    with cc:
        for i in range(cfg.concurrence_children):
            smach.Concurrence.add(f"C{i}", Trivial())
    return cc


def bench_concurrence(cfg: Config) -> Bench:
    cc = make_concurrence(cfg)

    def run() -> None:
        assert cc.execute() == "done"

    k = cfg.concurrence_children
    return Bench("concurrence", f"Concurrence of {k} trivial children", run, 1)


def _busy_loop(ready: Any, stop: Any) -> None:
    ready.set()
    x = 0
    while not stop.is_set():
        for _ in range(100_000):
            x += 1


def bench_concurrence_busy(cfg: Config) -> Result:
    cc = make_concurrence(cfg)

    def run() -> None:
        assert cc.execute() == "done"

    ctx = multiprocessing.get_context("spawn")
    ready, stop = ctx.Event(), ctx.Event()
    proc = ctx.Process(target=_busy_loop, args=(ready, stop), name="core_bench-busy", daemon=True)
    proc.start()
    try:
        if not ready.wait(30):
            raise RuntimeError("the busy-loop process did not start")
        time.sleep(0.05)
        progress(f"busy-loop process {proc.pid} running")
        k = cfg.concurrence_children
        bench = Bench("concurrence_busy", f"Concurrence of {k}, other core busy", run, 1)
        return run_interleaved([bench], cfg)["concurrence_busy"]
    finally:
        stop.set()
        proc.join(5)
        if proc.is_alive():
            proc.terminate()
            proc.join(5)
        progress(f"busy-loop process stopped (exit code {proc.exitcode})")


def bench_iterator(cfg: Config, name: str, n: int) -> Bench:
    items = list(range(n))
    it = smach.Iterator(
        outcomes=["done"],
        input_keys=[],
        output_keys=[],
        it=items,
        it_label="it_data",
        exhausted_outcome="done",
    )
    with it:
        smach.Iterator.set_contained_state("READ", ReadItem(), loop_outcomes=["continue"])

    def run() -> None:
        assert it.execute() == "done"

    return Bench(name, f"Iterator over {n} items", run, n)


def bench_nested(cfg: Config) -> Bench:
    depth = cfg.nesting
    inner: smach.State = Trivial()
    for _ in range(depth):
        sm = smach.StateMachine(outcomes=["done"])
        with sm:
            smach.StateMachine.add("CHILD", inner, transitions={"done": "done"})
        inner = sm
    root = inner
    assert isinstance(root, smach.StateMachine)

    def run() -> None:
        assert root.execute() == "done"

    return Bench("nested", f"{depth} nested StateMachines + leaf", run, 1)


def bench_nested_key(cfg: Config) -> Bench:
    depth = cfg.nesting
    inner: smach.State = Bump()
    for _ in range(depth):
        sm = smach.StateMachine(outcomes=["done"], input_keys=["x"], output_keys=["x"])
        with sm:
            smach.StateMachine.add("CHILD", inner, transitions={"done": "done"})
        inner = sm
    root = inner
    ud = smach.UserData({"x": 0})

    def run() -> None:
        before = ud.x
        assert root.execute(ud) == "done"
        assert ud.x == before + 1  # the key went down every level and came back up

    return Bench("nested_key", f"{depth} nested StateMachines, key x down and up", run, 1)


def _format_line(msg: Any) -> None:
    _line = f"[ INFO ] : {msg}"


class LoggedBench(Bench):
    """``bench`` with loggers installed during its own trials only (``set_loggers`` with
    a function that formats each line and drops it: what a logger costs at least)."""

    def __init__(self, bench: Bench) -> None:
        super().__init__(f"{bench.name}_logged", f"{bench.what}, loggers", bench.fn, bench.units)

    def prepare(self, cfg: Config) -> None:
        smach.set_loggers(_format_line, _format_line, _format_line, _format_line)
        try:
            super().prepare(cfg)
        finally:
            smach.log.restore_default_loggers()

    def trial(self) -> float:
        smach.set_loggers(_format_line, _format_line, _format_line, _format_line)
        try:
            return super().trial()
        finally:
            smach.log.restore_default_loggers()


# -- scenarios: preemption latency --------------------------------------------------------------
class WaitEvent(smach.State):
    def __init__(self, started: threading.Event) -> None:
        super().__init__(outcomes=["preempted"])
        self.started = started

    def execute(self, ud: Any) -> str:
        event = self.preempt_event
        self.started.set()
        event.wait()
        self.service_preempt()
        return "preempted"


class SleepState(WaitEvent):
    def execute(self, ud: Any) -> str:
        self.started.set()
        while not self.sleep(10.0):
            pass
        self.service_preempt()
        return "preempted"


class PollState(WaitEvent):
    def execute(self, ud: Any) -> str:
        self.started.set()
        while not self.preempt_requested():
            time.sleep(0.001)
        self.service_preempt()
        return "preempted"


def bench_preempt(cfg: Config, name: str, cls: type[WaitEvent], what: str) -> Result:
    """One sample per trial: request_preempt() from another thread -> execute() returns."""
    started = threading.Event()
    sm = smach.StateMachine(outcomes=["preempted"])
    with sm:
        smach.StateMachine.add("WAIT", cls(started), transitions={"preempted": "preempted"})
    rng = random.Random(1234)  # the request lands at a random point of the poll period
    samples = []
    for i in range(cfg.preempt_trials + 3):  # the first 3 are warm-up
        started.clear()
        delay = rng.uniform(0.001, 0.003)
        stamp: list[float] = []

        def requester(delay: float = delay, stamp: list[float] = stamp) -> None:
            started.wait()
            time.sleep(delay)
            stamp.append(time.perf_counter())
            sm.request_preempt()

        thread = threading.Thread(target=requester, name="preempt-requester")
        thread.start()
        outcome = sm.execute()
        end = time.perf_counter()
        thread.join()
        assert outcome == "preempted", outcome
        if i >= 3:
            samples.append((end - stamp[0]) * 1000.0)
    result = Result(name, what, cfg.preempt_trials, "ms", samples)
    progress(f"{name}: median {result.median:.3f} ms, p90 {result.p90:.3f} ms")
    return result


# -- floors -----------------------------------------------------------------------------------
def _f() -> None:
    pass


class _Obj:
    def m(self) -> None:
        pass


class _HSlot:
    __slots__ = ("next", "state")

    next: dict[str, Any]
    state: Trivial


def bench_handloop(cfg: Config) -> Bench:
    """The least a transition can cost in Python: execute(), one dict lookup, one check."""
    n = cfg.chain
    slots = [_HSlot() for _ in range(n)]
    for i, slot in enumerate(slots):
        slot.state = Trivial()
        slot.next = {"done": slots[i + 1] if i + 1 < n else "finished"}
    first = slots[0]
    ud = smach.UserData()

    def run() -> None:
        slot = first
        while True:
            target = slot.next[slot.state.execute(ud)]
            if target.__class__ is _HSlot:
                slot = target
                continue
            break

    return Bench("handloop", f"hand-written {n}-slot transition loop", run, n)


# -- peers --------------------------------------------------------------------------------------
def bench_py_trees(cfg: Config) -> Bench:
    import py_trees

    n = cfg.peer_py_trees
    root = py_trees.composites.Sequence(
        name="root",
        memory=True,
        children=[py_trees.behaviours.Success(name=f"B{i}") for i in range(n)],
    )
    root.setup_with_descendants()
    success = py_trees.common.Status.SUCCESS

    def run() -> None:
        root.tick_once()
        assert root.status == success

    return Bench(
        "peer_py_trees", f"py_trees {py_trees_version()} Sequence(memory=True) of {n}", run, n
    )


def py_trees_version() -> str:
    from importlib.metadata import version

    return version("py_trees")


def bench_transitions(cfg: Config) -> Bench:
    import transitions

    n = cfg.peer_transitions

    class Model:
        pass

    model = Model()
    transitions.Machine(
        model=model,
        states=["A", "B"],
        transitions=[
            {"trigger": "toggle", "source": "A", "dest": "B"},
            {"trigger": "toggle", "source": "B", "dest": "A"},
        ],
        initial="A",
        auto_transitions=False,
    )
    toggle = model.toggle  # type: ignore[attr-defined]

    def run() -> None:
        for _ in range(n):
            toggle()

    what = f"transitions {transitions.__version__} Machine, {n} changes"
    return Bench("peer_transitions", what, run, n)


# -- report ---------------------------------------------------------------------------------------
def fmt(value: float) -> str:
    if value >= 100:
        return f"{value:.0f}"
    if value >= 10:
        return f"{value:.1f}"
    if value >= 1:
        return f"{value:.2f}"
    return f"{value:.3f}"


UNITS = {
    "chain": "us/transition",
    "remap_loop": "us/transition",
    "concurrence": "us/execution",
    "concurrence_busy": "us/execution",
    "iterator_small": "us/item",
    "iterator_medium": "us/item",
    "iterator_large": "us/item",
    "nested": "us/execution",
    "nested_key": "us/execution",
    "nested_logged": "us/execution",
    "nested_key_logged": "us/execution",
    "preempt_event": "ms",
    "preempt_sleep": "ms",
    "preempt_poll": "ms",
    "call_function": "ns/call",
    "call_method": "ns/call",
    "handloop": "us/transition",
    "peer_py_trees": "us/behaviour",
    "peer_transitions": "us/change",
}


def table_lines(results: dict[str, Result]) -> list[str]:
    """The table of the scenarios measured (in SCENARIOS order)."""
    head = (
        f"{'scenario':<18} {'size':>7}  {'unit':<14} {'median':>8} {'min':>8} {'p90':>8}"
        f" {'calls':>7}"
    )
    out = [head, "-" * len(head)]
    for name in SCENARIOS:
        if name not in results:
            continue
        res = results[name]
        scale = 1000.0 if UNITS[name].startswith("ns") else 1.0
        size = res.size if not name.startswith("call_") else 1
        calls = f"{res.calls:.1f}" if res.calls is not None else "-"
        out.append(
            f"{name:<18} {size:>7}  {UNITS[name]:<14} {fmt(res.median * scale):>8} "
            f"{fmt(res.min * scale):>8} {fmt(res.p90 * scale):>8} {calls:>7}"
        )
        if name in ("nested_key_logged", "preempt_poll", "handloop"):
            out.append("")
    return out


def report(results: dict[str, Result], cfg: Config, load: tuple[float, float]) -> dict[str, Any]:
    r = results
    out: list[str] = []
    add = out.append
    mode = "QUICK (small sizes, indicative only)" if cfg.quick else "full"
    add("")
    add(f"smach core benchmark - mode: {mode}")
    add(
        f"python {platform.python_version()} ({platform.python_implementation()}), "
        f"{os.cpu_count()} cores, {platform.machine()}, {platform.system()} {platform.release()}"
    )
    add(
        f"1-min load average before/after the run: {load[0]:.2f} / {load[1]:.2f}"
        + ("  (machine not idle: numbers inflated)" if load[0] > 0.5 else "")
    )
    call_ns = r["call_function"].median * 1000
    add(
        f"machine speed: call_function {call_ns:.1f} ns vs {QUIET_CALL_NS} ns when idle "
        f"-> this run ran {call_ns / QUIET_CALL_NS:.2f}x slower than an idle machine"
        + (
            "  (marginal PASS/MISS below are not reliable)"
            if call_ns > 1.25 * QUIET_CALL_NS
            else ""
        )
    )
    add(
        f"{cfg.trials} interleaved trials per scenario (>= {cfg.min_trial_s * 1000:.0f} ms each), "
        f"{cfg.preempt_trials} trials per preemption scenario"
    )
    add("")
    out += table_lines(r)
    add("")

    # Floors.
    add("In bare function calls ('calls' column: per round, the scenario's sample divided by")
    add("the call_function sample of the same round; median over rounds):")
    for name in ("nested", "nested_key", "nested_logged", "nested_key_logged"):
        per_level = r[name].median / (cfg.nesting + 1)
        calls = r[name].calls
        add(
            f"  {name}: {fmt(per_level)} us per level"
            + (f" = {calls / (cfg.nesting + 1):.0f} calls" if calls is not None else "")
        )
    add(
        f"  handloop (pure-Python floor of a transition) = "
        f"{fmt(r['handloop'].median)} us; chain = {r['chain'].median / r['handloop'].median:.1f}x "
        f"handloop"
    )
    add("")

    # Peers.
    peers = []
    add("Peers (same run; ratio = peer median / our median, > 1 means smach is faster):")
    for ours, peer, label in (
        ("chain", "peer_py_trees", "chain transition vs py_trees behaviour"),
        ("chain", "peer_transitions", "chain transition vs transitions change"),
        ("remap_loop", "peer_transitions", "remapped loop transition vs transitions change"),
    ):
        ratio = r[peer].median / r[ours].median
        peers.append({"ours": ours, "peer": peer, "ratio": ratio})
        add(
            f"  {label:<48} {fmt(r[ours].median):>7} us vs {fmt(r[peer].median):>7} us"
            f"  -> {ratio:5.2f}x"
        )
    add("")

    # Original.
    add("Original SMACH core (constants: medians measured earlier on this machine):")
    vs_original: list[dict[str, Any]] = []
    for name in (
        "chain",
        "remap_loop",
        "concurrence",
        "concurrence_busy",
        "iterator_medium",
        "nested",
    ):
        ref = ORIGINAL[name]
        mine = r[name].median
        if isinstance(ref, tuple):
            lo, hi = ref
            add(
                f"  {name:<18} original {fmt(lo)}-{fmt(hi)} {UNITS[name]:<13} ours {fmt(mine):>8}"
                f"  -> {lo / mine:.0f}x-{hi / mine:.0f}x faster"
            )
            vs_original.append(
                {
                    "name": name,
                    "original": [lo, hi],
                    "ours": mine,
                    "speedup": [lo / mine, hi / mine],
                }
            )
        else:
            add(
                f"  {name:<18} original {fmt(ref):>9} {UNITS[name]:<13} ours {fmt(mine):>8}"
                f"  -> {ref / mine:.1f}x faster"
            )
            vs_original.append({"name": name, "original": ref, "ours": mine, "speedup": ref / mine})
    add("  preempt            original: bounded by the state's poll period (no event to wait on)")
    add("")

    # Targets.
    targets = []

    def target(label: str, ok: bool, detail: str) -> None:
        targets.append({"target": label, "pass": ok, "detail": detail})
        add(f"  {'PASS' if ok else 'MISS'}  {label:<44} {detail}")

    add("Targets" + (" (quick mode: sizes differ, indicative only)" if cfg.quick else "") + ":")
    for name, factor in SPEEDUP_TARGETS.items():
        ref = ORIGINAL[name]
        assert isinstance(ref, float)
        speedup = ref / r[name].median
        target(
            f"{name}: >= {factor:.0f}x faster than original",
            speedup >= factor,
            f"{speedup:.1f}x (needs <= {fmt(ref / factor)} {UNITS[name]}, "
            f"got {fmt(r[name].median)})",
        )
    busy_lo = ORIGINAL["concurrence_busy"][0]  # type: ignore[index]
    speedup = busy_lo / r["concurrence_busy"].median
    target(
        "concurrence_busy: >= 10x vs original's best",
        speedup >= 10,
        f"{speedup:.0f}x vs {fmt(busy_lo)} us (got {fmt(r['concurrence_busy'].median)} us)",
    )
    small, medium, large = (r[f"iterator_{s}"].median for s in ("small", "medium", "large"))
    worst = max(small, medium, large)
    target(
        f"iterator: < {ITERATOR_MAX_US:g} us/item at every size",
        worst < ITERATOR_MAX_US,
        f"worst {fmt(worst)} us/item",
    )
    growth = large / small
    target(
        f"iterator: linear (x100 items: <= {ITERATOR_LINEARITY}x us/item)",
        growth <= ITERATOR_LINEARITY,
        f"us/item {fmt(small)} -> {fmt(medium)} -> {fmt(large)} ({growth:.2f}x)",
    )
    for name in ("preempt_event", "preempt_sleep"):
        res = r[name]
        target(
            f"{name}: median latency < {PREEMPT_EVENT_MAX_MS} ms",
            res.median < PREEMPT_EVENT_MAX_MS,
            f"median {res.median:.3f} ms, p90 {res.p90:.3f} ms",
        )
    add("")
    print("\n".join(out), flush=True)
    return {"peers": peers, "vs_original": vs_original, "targets": targets}


# -- main -----------------------------------------------------------------------------------------
def wanted(name: str, cfg: Config) -> bool:
    """Whether ``--only`` keeps the scenario ``name`` (all without it; always the floor)."""
    if not cfg.only or name == "call_function":
        return True
    return name in cfg.only or name.removesuffix("_logged") in cfg.only


# Throughput scenarios whose work runs in other threads too (wall time even with --cpu-time).
THREADED = frozenset({"concurrence"})


def run_all(cfg: Config) -> dict[str, Result]:
    progress("building the scenarios")
    nested, nested_key = bench_nested(cfg), bench_nested_key(cfg)
    benches = [
        CallBench("call_function", "bare function call", "f()", cfg.cpu_time),
        CallBench("call_method", "trivial method call", "o.m()", cfg.cpu_time),
        bench_handloop(cfg),
        bench_chain(cfg),
        bench_remap_loop(cfg),
        bench_concurrence(cfg),
        *(
            bench_iterator(cfg, name, n)
            for name, n in zip(
                ("iterator_small", "iterator_medium", "iterator_large"),
                cfg.iterator_sizes,
                strict=True,
            )
        ),
        nested,
        nested_key,
        LoggedBench(nested),
        LoggedBench(nested_key),
        bench_py_trees(cfg),
        bench_transitions(cfg),
    ]
    benches = [bench for bench in benches if wanted(bench.name, cfg)]
    if cfg.cpu_time:
        for bench in benches:
            if bench.name not in THREADED:
                bench.clock = time.thread_time_ns
    progress(f"throughput scenarios, {cfg.trials} interleaved rounds")
    results = run_interleaved(benches, cfg)
    if wanted("concurrence_busy", cfg):
        progress("concurrence with the other core busy")
        results["concurrence_busy"] = bench_concurrence_busy(cfg)
    preempts = (
        ("preempt_event", WaitEvent, "state waits on preempt_event"),
        ("preempt_sleep", SleepState, "state in self.sleep(10)"),
        ("preempt_poll", PollState, "state polls every 1 ms"),
    )
    for name, cls, what in preempts:
        if wanted(name, cfg):
            progress(f"preemption latency: {name}")
            results[name] = bench_preempt(cfg, name, cls, what)
    return results


def _deeper(frames: int, fn: Callable[[], float]) -> float:
    """``fn()`` called ``frames`` Python frames deeper than here."""
    return _deeper(frames - 1, fn) if frames else fn()


STACK_DEPTHS = range(0, 161, 4)  # (a frame of _deeper: 80 bytes; a chunk: 16 KiB)


def stack_sweep(cfg: Config, json_out: str | None) -> int:
    """The nesting scenarios, each run from a caller ``k`` frames deeper (issue 39).

    A run whose Python frames span a boundary of CPython's frame stack (16 KiB chunks,
    a chunk freed as soon as the frame at its base returns) pays an ``mmap``, a
    ``munmap`` and page faults on every execution, more where calls are made right at
    the boundary; where the boundaries fall depends on how deep the caller is. So the
    cost of one scenario at each caller depth, and its minor page faults per execution
    (``getrusage``), show whether a run's speed depends on where it is called from.
    """
    nested, nested_key = bench_nested(cfg), bench_nested_key(cfg)
    benches = [nested, nested_key, LoggedBench(nested), LoggedBench(nested_key)]
    benches.append(bench_chain(replace(cfg, chain=200)))  # (a flat loop, for reference)
    trials = 3
    rows: list[dict[str, Any]] = []
    for bench in benches:
        bench.prepare(cfg)
    for depth in STACK_DEPTHS:
        row: dict[str, Any] = {"depth": depth}
        for bench in benches:

            def timed(bench: Bench = bench, row: dict[str, Any] = row) -> float:
                bench.trial()  # (warm at this depth)
                before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
                best = min(bench.trial() for _ in range(trials))
                faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
                row[f"{bench.name}_faults"] = faults / (trials * bench.reps * bench.units)
                return best

            row[bench.name] = _deeper(depth, timed)
        rows.append(row)
        progress(f"caller {depth} frames deeper: done")
    head = f"{'caller depth':>12}" + "".join(f" {b.name + ' us (faults)':>26}" for b in benches)
    lines = [
        "",
        f"Nesting scenarios by caller stack depth (best of {trials} trials; minor page faults "
        "per execution in parentheses):",
        "",
        head,
        "-" * len(head),
    ]
    for row in rows:
        cells = "".join(
            f" {fmt(row[b.name]):>17} ({row[b.name + '_faults']:>6.2f})" for b in benches
        )
        lines.append(f"{row['depth']:>12}{cells}")
    lines.append("")
    for bench in benches:
        values = [row[bench.name] for row in rows]
        faulty = sum(1 for row in rows if row[bench.name + "_faults"] >= 0.5)
        lines.append(
            f"  {bench.name:<18} median {fmt(sorted(values)[len(values) // 2])}, best "
            f"{fmt(min(values))}, worst {fmt(max(values))} us ({max(values) / min(values) - 1:.0%}"
            f" over the best); page faults at {faulty} of {len(rows)} depths"
        )
    print("\n".join(lines), flush=True)
    if json_out:
        Path(json_out).write_text(json.dumps({"stack_sweep": rows}, indent=2), encoding="utf-8")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, a few seconds")
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    parser.add_argument(
        "--processes",
        type=int,
        default=6,
        metavar="N",
        help="measure in N fresh processes, one after the other, and report each "
        "scenario's spread over them (default 6; 1: measure in this process)",
    )
    parser.add_argument(
        "--original",
        metavar="DIR",
        help="a checkout of the original SMACH (ros/executive_smach): measure its core in "
        "this run, in every logging configuration (see core_compare.py)",
    )
    parser.add_argument(
        "--original-git",
        metavar="URL",
        help="clone the original SMACH from URL into a temporary directory and measure it",
    )
    parser.add_argument(
        "--only",
        metavar="NAMES",
        help="only these scenarios (comma-separated, e.g. nested,nested_key,chain; a name "
        "keeps its _logged variant too), in the table and in the comparison",
    )
    parser.add_argument(
        "--cpu-time",
        action="store_true",
        help="time the single-threaded scenarios in thread CPU time (robust on a loaded "
        "machine: time spent descheduled is not counted)",
    )
    parser.add_argument(
        "--stack-sweep",
        action="store_true",
        help="only the nesting scenarios and a flat chain, each run from callers 0, 4, ..., "
        "160 frames deep in this process: us and page faults per execution at each depth",
    )
    args = parser.parse_args(argv)
    if args.stack_sweep:
        return stack_sweep(QUICK if args.quick else FULL, args.json)
    if args.processes < 1:
        parser.error("--processes needs at least 1")
    cfg = QUICK if args.quick else FULL
    if args.cpu_time:
        cfg = replace(cfg, cpu_time=True)
    if args.only:
        cfg = replace(cfg, only=tuple(args.only.split(",")))
    with tempfile.TemporaryDirectory(prefix="core_bench-") as tmp:
        original_dir = args.original
        if args.original_git:
            progress(f"cloning {args.original_git}")
            original_dir = str(core_compare.clone(args.original_git, Path(tmp)))
        if args.processes > 1:
            worker = [
                *(["--quick"] if args.quick else []),
                *(["--cpu-time"] if args.cpu_time else []),
            ]
            worker += [*(["--only", args.only] if args.only else [])]
            worker += [*(["--original", original_dir] if original_dir else [])]
            return core_spread.run(
                Path(__file__), worker, args.processes, cfg, args.json, progress, UNITS
            )
        original = core_compare.load_original(Path(original_dir)) if original_dir else None
        return measure(args, cfg, original)


def measure(args: argparse.Namespace, cfg: Config, original: Any) -> int:
    """Measure in this process; print the report; write ``args.json``."""
    # No INFO logging during measurement: keep the default loggers, silence the
    # Python loggers the libraries use (smach logs INFO only when its logger is on).
    levels = {}
    for logger_name in ("smach", "transitions", "py_trees"):
        logger = logging.getLogger(logger_name)
        levels[logger_name] = logger.level
        logger.setLevel(logging.WARNING)
    assert not smach.log.info_enabled(), "smach INFO logging must be off while measuring"

    load_before = os.getloadavg()[0]
    if load_before > 0.5:
        progress(
            f"WARNING: 1-min load average is {load_before:.2f}; other processes compete for "
            "the cores and inflate the numbers (and the 'busy core' scenario)"
        )
    started = time.perf_counter()
    try:
        results = run_all(cfg)
        vs_original = None
        if original is not None:
            progress("the original SMACH core, same run")
            vs_original = core_compare.compare(
                cfg, smach, original, Bench, run_interleaved, progress
            )
    finally:
        for logger_name, level in levels.items():
            logging.getLogger(logger_name).setLevel(level)
    load = (load_before, os.getloadavg()[0])
    progress(f"done in {time.perf_counter() - started:.1f} s")
    if cfg.only:  # (the scenarios asked for; the floors, peers and targets need them all)
        print("\n".join(["", *table_lines(results)]), flush=True)
        summary: dict[str, Any] = {}
    else:
        summary = report(results, cfg, load)
    if vs_original is not None:
        slowdown = results["call_function"].median * 1000 / QUIET_CALL_NS
        lines, summary["same_run_original"] = core_compare.report(vs_original, cfg, slowdown)
        print("\n".join(lines), flush=True)

    if args.json:
        doc = {
            "mode": "quick" if cfg.quick else "full",
            "python": platform.python_version(),
            "cores": os.cpu_count(),
            "pid": os.getpid(),
            "load_average_1min": {"before": load[0], "after": load[1]},
            "config": asdict(cfg),
            "results": {name: asdict(res) for name, res in results.items()},
            "original": {k: list(v) if isinstance(v, tuple) else v for k, v in ORIGINAL.items()},
            "original_same_run": None
            if vs_original is None
            else {
                config: {name: asdict(res) for name, res in res_map.items()}
                for config, res_map in vs_original.items()
            },
            **summary,
        }
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=2)
        progress(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
