"""The smach core against the original SMACH core, both measured in the same run.

Used by ``core_bench.py --original DIR`` (or ``--original-git URL``, which clones the
original into a temporary directory first). The original's core package (ros/
executive_smach: ``smach/smach`` on the ros2 branch, ``smach/src/smach`` on noetic) is
imported beside ours as a second module object, so the trials of both alternate in one
process on one machine state.

Every scenario runs in three logging configurations, each applied to both cores:

* ``default``: each library's own default. Ours writes no INFO line (the ``smach``
  Python logger is at WARNING, as an unconfigured ``logging`` is); the original's
  default loggers ``print`` every line (stdout goes to ``os.devnull`` meanwhile).
* ``noop``: ``set_loggers`` with four functions that do nothing.
* ``format``: ``set_loggers`` with four functions that format their message into a
  line (``f"[ INFO ] : {msg}"``) and drop it.

and in two modes: ``repeated`` (one machine executed again and again) and ``first``
(a freshly built machine executed once; the build is not timed, a separate
``build`` row times it).

``core_bench.py --original DIR --only nested,nested_key`` runs only these scenarios
of the comparison; ``--cpu-time`` times the single-threaded ones in the running
thread's CPU time (``time.thread_time_ns``) instead of wall time, so that on a loaded
machine the time spent descheduled by other processes is not counted (Concurrence,
which runs children in pool threads too, stays in wall time).
"""

from __future__ import annotations

import contextlib
import dataclasses
import gc
import importlib
import math
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

CONFIGS = ("default", "noop", "format")
# Directories that may hold the original's ``smach`` package, under a checkout.
LAYOUTS = ("smach/smach", "smach/src/smach", "smach", "src/smach")

# Aims (issue 19): in every configuration and mode.
SPEEDUP_AIMS = {
    "chain": 4.0,
    "remap_loop": 4.0,
    "nested": 4.0,
    "nested_key": 4.0,  # issue 28: nested machines with a key passed down
    "concurrence": 10.0,
}
# Scenarios whose work runs in other threads too (timed in wall time even with --cpu-time).
THREADED = frozenset({"concurrence"})
# Which class of the core a scenario needs (an original checkout without it skips it).
NEEDS = {"iterator": "Iterator", "concurrence": "Concurrence"}
ITERATOR_MAX_US = 2.0
ITERATOR_LINEARITY = 1.5


# -- the original -----------------------------------------------------------------------------
def find_package(root: Path) -> Path:
    """The directory to put on ``sys.path`` so that ``import smach`` finds the original."""
    for rel in LAYOUTS:
        pkg = root / rel
        if (pkg / "__init__.py").is_file() and (pkg / "state_machine.py").is_file():
            return pkg.parent
    looked = ", ".join(f"{root / rel}/__init__.py" for rel in LAYOUTS)
    raise SystemExit(f"no original smach package under {root} (looked for {looked})")


def clone(url: str, into: Path) -> Path:
    """``git clone --depth 1 url`` into ``into``/original (this run's copy)."""
    dest = into / "original"
    subprocess.run(["git", "clone", "--quiet", "--depth", "1", url, str(dest)], check=True)
    return dest


def load_original(root: Path) -> ModuleType:
    """Import the original ``smach`` package found under ``root`` beside ours.

    The original's modules ``import smach`` and look everything up on that module at
    call time. So it is imported while ``sys.modules["smach"]`` is its own; ours is
    put back afterwards and each keeps its own package.
    """
    path = str(find_package(root))
    ours = {k: v for k, v in sys.modules.items() if k == "smach" or k.startswith("smach.")}
    for name in ours:
        del sys.modules[name]
    sys.path.insert(0, path)
    try:
        original = importlib.import_module("smach")
    finally:
        sys.path.remove(path)
        for name in [k for k in sys.modules if k == "smach" or k.startswith("smach.")]:
            del sys.modules[name]
        sys.modules.update(ours)
    if not hasattr(threading.Thread, "isAlive"):
        # Older originals' Concurrence calls Thread.isAlive (removed in Python 3.9).
        threading.Thread.isAlive = threading.Thread.is_alive  # type: ignore[attr-defined]
    return original


# -- logging configurations ---------------------------------------------------------------------
def _noop(msg: Any) -> None:
    pass


def _format(msg: Any) -> None:
    _line = f"[ INFO ] : {msg}"


@contextlib.contextmanager
def logging_config(name: str, ours: ModuleType, original: ModuleType) -> Iterator[None]:
    """Install one configuration on both cores (restoring the defaults afterwards)."""
    defaults = (original.loginfo, original.logwarn, original.logdebug, original.logerr)
    saved = sys.stdout
    try:
        if name == "default":
            ours.log.restore_default_loggers()
            sys.stdout = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115
        else:
            fn = _noop if name == "noop" else _format
            ours.set_loggers(fn, fn, fn, fn)
            original.set_loggers(fn, fn, fn, fn)
        yield
    finally:
        if sys.stdout is not saved:
            sys.stdout.close()
            sys.stdout = saved
        ours.log.restore_default_loggers()
        original.set_loggers(*defaults)


# -- scenarios, written once against the SMACH API both cores share ----------------------------
def state_classes(m: ModuleType) -> SimpleNamespace:
    class Trivial(m.State):  # type: ignore[misc,name-defined]
        def __init__(self) -> None:
            m.State.__init__(self, outcomes=["done"])

        def execute(self, ud: Any) -> str:
            return "done"

    class Copy(m.State):  # type: ignore[misc,name-defined]
        def __init__(self, limit: int | None) -> None:
            m.State.__init__(
                self, outcomes=["next", "done"], input_keys=["inp"], output_keys=["out"]
            )
            self.limit = limit

        def execute(self, ud: Any) -> str:
            value = ud.inp + 1
            ud.out = value
            return "done" if self.limit is not None and value >= self.limit else "next"

    class Bump(m.State):  # type: ignore[misc,name-defined]
        def __init__(self) -> None:
            m.State.__init__(self, outcomes=["done"], input_keys=["x"], output_keys=["x"])

        def execute(self, ud: Any) -> str:
            ud.x = ud.x + 1
            return "done"

    class ReadItem(m.State):  # type: ignore[misc,name-defined]
        def __init__(self) -> None:
            m.State.__init__(self, outcomes=["continue"], input_keys=["it_data"])

        def execute(self, ud: Any) -> str:
            ud.it_data  # noqa: B018 - the read is the work
            return "continue"

    return SimpleNamespace(Trivial=Trivial, Copy=Copy, Bump=Bump, ReadItem=ReadItem)


Runner = Callable[[], None]


def build_chain(m: ModuleType, n: int) -> Runner:
    s = state_classes(m)
    sm = m.StateMachine(outcomes=["finished"])
    with sm:
        for i in range(n):
            target = f"S{i + 1}" if i + 1 < n else "finished"
            m.StateMachine.add(f"S{i}", s.Trivial(), transitions={"done": target})

    def run() -> None:
        assert sm.execute() == "finished"

    return run


def build_remap_loop(m: ModuleType, n: int) -> Runner:
    s = state_classes(m)
    sm = m.StateMachine(outcomes=["finished"])
    with sm:
        m.StateMachine.add(
            "A",
            s.Copy(None),
            transitions={"next": "B", "done": "finished"},
            remapping={"inp": "x", "out": "y"},
        )
        m.StateMachine.add(
            "B",
            s.Copy(n),
            transitions={"next": "A", "done": "finished"},
            remapping={"inp": "y", "out": "x"},
        )
    data = sm.userdata

    def run() -> None:
        data.x = 0
        assert sm.execute() == "finished"
        assert data.x == n

    return run


def build_nested(m: ModuleType, depth: int) -> Runner:
    inner: Any = state_classes(m).Trivial()
    for _ in range(depth):
        sm = m.StateMachine(outcomes=["done"])
        with sm:
            m.StateMachine.add("CHILD", inner, transitions={"done": "done"})
        inner = sm
    root = inner

    def run() -> None:
        assert root.execute() == "done"

    return run


def build_nested_key(m: ModuleType, depth: int) -> Runner:
    """``build_nested`` with a userdata key passed down every level and back up."""
    inner: Any = state_classes(m).Bump()
    for _ in range(depth):
        sm = m.StateMachine(outcomes=["done"], input_keys=["x"], output_keys=["x"])
        with sm:
            m.StateMachine.add("CHILD", inner, transitions={"done": "done"})
        inner = sm
    root = inner
    ud = m.UserData()
    ud["x"] = 0

    def run() -> None:
        before = ud["x"]
        assert root.execute(ud) == "done"
        assert ud["x"] == before + 1

    return run


def build_iterator(m: ModuleType, n: int) -> Runner:
    it = m.Iterator(
        outcomes=["done"],
        input_keys=[],
        output_keys=[],
        it=list(range(n)),
        it_label="it_data",
        exhausted_outcome="done",
    )
    with it:
        m.Iterator.set_contained_state(
            "READ", state_classes(m).ReadItem(), loop_outcomes=["continue"]
        )

    def run() -> None:
        assert it.execute(m.UserData()) == "done"

    return run


def build_concurrence(m: ModuleType, k: int) -> Runner:
    s = state_classes(m)
    cc = m.Concurrence(outcomes=["done"], default_outcome="done")
    with cc:
        for i in range(k):
            m.Concurrence.add(f"C{i}", s.Trivial())

    def run() -> None:
        assert cc.execute() == "done"

    return run


@dataclass(frozen=True)
class Scenario:
    name: str
    what: str
    unit: str
    build: Callable[[ModuleType, int], Runner]
    size: int  # our size
    original_size: int  # the original's (smaller where it is quadratic)
    units_per_run: bool = True  # divide by the size (per transition / item)


def scenarios(cfg: Any) -> list[Scenario]:
    """The scenarios, or only those named in ``cfg.only`` (when it has any)."""
    only = getattr(cfg, "only", ())
    return [sc for sc in _all_scenarios(cfg) if not only or sc.name in only]


def _all_scenarios(cfg: Any) -> list[Scenario]:
    small, medium, large = cfg.iterator_sizes
    k = cfg.concurrence_children
    return [
        Scenario("chain", f"{cfg.chain}-state chain", "us/transition", build_chain, cfg.chain, cfg.chain),
        Scenario("remap_loop", "2-state loop, remapped read + write", "us/transition", build_remap_loop, cfg.loop, cfg.loop),
        Scenario("nested", f"{cfg.nesting} nested StateMachines + leaf", "us/execution", build_nested, cfg.nesting, cfg.nesting, False),
        Scenario("nested_key", f"{cfg.nesting} nested StateMachines, key passed down", "us/execution", build_nested_key, cfg.nesting, cfg.nesting, False),
        Scenario("iterator_small", f"Iterator, {small} items", "us/item", build_iterator, small, small),
        Scenario("iterator_medium", f"Iterator, {medium} items", "us/item", build_iterator, medium, 0),
        Scenario("iterator_large", f"Iterator, {large} items", "us/item", build_iterator, large, 0),
        Scenario("concurrence", f"Concurrence of {k}", "us/execution", build_concurrence, k, k, False),
    ]  # fmt: skip


# -- timing -------------------------------------------------------------------------------------
class FirstRun:
    """A fresh machine executed once per sample: built outside the timed region."""

    clock: Callable[[], int] = staticmethod(time.perf_counter_ns)  # (see Bench.clock)

    def __init__(self, name: str, what: str, build: Callable[[], Runner], units: int) -> None:
        self.name = name
        self.what = what
        self.build = build
        self.units = units
        self.reps = 1
        self.samples: list[float] = []

    def prepare(self, cfg: Any) -> None:
        run = self.build()
        t0 = time.perf_counter()
        run()
        once = max(time.perf_counter() - t0, 1e-7)
        # At most 25 fresh machines a sample: building them (untimed) is the slow part.
        self.reps = max(1, min(25, math.ceil(cfg.min_trial_s / once)))

    def trial(self) -> float:
        runs = [self.build() for _ in range(self.reps)]
        clock = self.clock
        gc.collect()
        gc.disable()
        try:
            start = clock()
            for run in runs:
                run()
            elapsed = clock() - start
        finally:
            gc.enable()
        return elapsed / 1000.0 / (self.reps * self.units)


class Build(FirstRun):
    """Building a machine (construction and ``close()``), per state."""

    def prepare(self, cfg: Any) -> None:
        t0 = time.perf_counter()
        self.build()
        once = max(time.perf_counter() - t0, 1e-7)
        self.reps = max(1, min(5, math.ceil(cfg.min_trial_s / once)))

    def trial(self) -> float:
        gc.collect()
        gc.disable()
        clock = self.clock
        try:
            start = clock()
            for _ in range(self.reps):
                self.build()
            elapsed = clock() - start
        finally:
            gc.enable()
        return elapsed / 1000.0 / (self.reps * self.units)


def compare(
    cfg: Any,
    ours: ModuleType,
    original: ModuleType,
    bench_cls: Any,
    run_interleaved: Callable[[list[Any], Any], dict[str, Any]],
    progress: Callable[[str], None],
) -> dict[str, dict[str, Any]]:
    """Every scenario x mode x implementation, per configuration: ``{config: results}``.

    Result names are ``scenario/mode/impl`` (impl: ``ours`` or ``original``).
    """
    out: dict[str, dict[str, Any]] = {}
    cfg = dataclasses.replace(cfg, trials=cfg.compare_trials)
    for config in CONFIGS:
        benches: list[Any] = []
        with logging_config(config, ours, original):
            for sc in scenarios(cfg):
                start = len(benches)
                for impl, m, size in (
                    ("ours", ours, sc.size),
                    ("original", original, sc.original_size),
                ):
                    if not size or not hasattr(m, NEEDS.get(sc.name.split("_")[0], "State")):
                        continue
                    units = size if sc.units_per_run else 1
                    name = f"{sc.name}/repeated/{impl}"
                    benches.append(bench_cls(name, sc.what, sc.build(m, size), units))
                    if sc.name in ("iterator_medium", "iterator_large"):
                        continue

                    def fresh(build: Any = sc.build, m: Any = m, size: int = size) -> Runner:
                        return build(m, size)  # type: ignore[no-any-return]

                    benches.append(FirstRun(f"{sc.name}/first/{impl}", sc.what, fresh, units))
                    if sc.name == "chain":

                        def make(m: Any = m, size: int = size) -> Runner:
                            return build_chain(m, size)

                        benches.append(Build(f"chain/build/{impl}", sc.what, make, size))
                if getattr(cfg, "cpu_time", False) and sc.name not in THREADED:
                    for bench in benches[start:]:
                        bench.clock = time.thread_time_ns
            progress(f"vs original, logging '{config}': {len(benches)} scenario(s)")
            out[config] = run_interleaved(benches, cfg)
    return out


def paired_ratio(a: Any, b: Any) -> float:
    """Median over rounds of ``a``'s sample / ``b``'s sample of the same round.

    The trials of one round run back to back, so a machine that slows down or speeds
    up during the run (shared, virtual) changes both alike; the ratio stays put.
    """
    pairs = zip(a.samples, b.samples, strict=True)
    ratios: list[float] = sorted(float(x) / float(y) for x, y in pairs if y > 0)
    n = len(ratios)
    return ratios[n // 2] if n % 2 else (ratios[n // 2 - 1] + ratios[n // 2]) / 2


def report(
    results: dict[str, dict[str, Any]], cfg: Any, slowdown: float = 1.0
) -> tuple[list[str], dict[str, Any]]:
    """Lines of the comparison table and the aims, and the JSON summary.

    ``slowdown``: how much slower than idle the machine ran (bare-call floor of the same
    run); the iterator's absolute aim is judged on the idle estimate, value / slowdown.
    """
    lines = [
        "Against the original SMACH core (measured in this run; medians in us; ratio = "
        "median over rounds of original / ours, > 1 means smach is faster):",
        "",
    ]
    head = f"{'scenario':<16} {'mode':<9} {'unit':<14}" + "".join(
        f" {c + ' ours':>12} {'original':>9} {'ratio':>6}" for c in CONFIGS
    )
    lines += [head, "-" * len(head)]
    rows: list[dict[str, Any]] = []
    for sc in scenarios(cfg):
        for mode in ("repeated", "first", "build"):
            key = f"{sc.name}/{mode}"
            if f"{key}/ours" not in results[CONFIGS[0]]:
                continue
            unit = "us/state" if mode == "build" else sc.unit
            cells = ""
            row: dict[str, Any] = {"scenario": sc.name, "mode": mode, "unit": unit}
            for c in CONFIGS:
                r = results[c]
                ours = r[f"{key}/ours"].median
                orig = r[f"{key}/original"].median if f"{key}/original" in r else None
                ratio = paired_ratio(r[f"{key}/original"], r[f"{key}/ours"]) if orig else None
                shown = f"{orig:>9.4g}" if orig is not None else f"{'-':>9}"
                cells += f" {ours:>12.3g} {shown}" + (f" {ratio:>5.1f}x" if ratio else f" {'-':>6}")
                row[c] = {"ours": ours, "original": orig, "ratio": ratio}
            rows.append(row)
            lines.append(f"{sc.name:<16} {mode:<9} {unit:<14}{cells}")
    lines += ["", "Aims (every logging configuration and mode):"]
    aims: list[dict[str, Any]] = []

    def aim(label: str, ok: bool, detail: str) -> None:
        aims.append({"aim": label, "pass": ok, "detail": detail})
        lines.append(f"  {'PASS' if ok else 'MISS'}  {label:<52} {detail}")

    for name, factor in SPEEDUP_AIMS.items():
        for row in rows:
            if row["scenario"] != name or row["mode"] == "build":
                continue
            ratios = [row[c]["ratio"] for c in CONFIGS]
            present = [r for r in ratios if r is not None]
            if not present:  # (the original checkout lacks this container)
                continue
            aim(
                f"{name} ({row['mode']}): >= {factor:g}x the original",
                min(present) >= factor,
                "  ".join(
                    f"{c} {r:.1f}x" if r is not None else f"{c} -"
                    for c, r in zip(CONFIGS, ratios, strict=True)
                ),
            )
    for c in CONFIGS:
        r = results[c]
        if any(f"iterator_{s}/repeated/ours" not in r for s in ("small", "medium", "large")):
            continue  # (not measured in this run: --only)
        sizes = [r[f"iterator_{s}/repeated/ours"] for s in ("small", "medium", "large")]
        per_item = [res.median for res in sizes]
        growth = paired_ratio(sizes[2], sizes[0])
        idle = max(per_item) / slowdown
        aim(
            f"iterator ({c}): <= {ITERATOR_MAX_US:g} us/item (idle est.), linear",
            idle <= ITERATOR_MAX_US and growth <= ITERATOR_LINEARITY,
            " -> ".join(f"{v:.3g}" for v in per_item)
            + f" us/item, idle est. <= {idle:.2f} (x{growth:.2f} per item from 1k to 100k)",
        )
    return lines, {"rows": rows, "aims": aims}
