"""Measure the order mission on robosim_hospital: is every order accounted for?

Runs ``plan-bridge run domains/robosim_hospital --orders orders/O.yaml --events
events/E.yaml --seed S --fail-rate R --json`` for every orders file O, events file E
and seed S (the planned order mission, as a user runs it), reads each order's life
from the ``[order]`` lines and the ``--json`` figures, and prints per (E, O):

- the orders that arrived, and what became of them: done, failed, refused, cancelled,
  **lost** (never final: must be 0), **done twice** (must be 0);
- which of the orders not done *could not* be done: refused (not accepted: an unknown
  name, or no robot can reach the goal) or failed with no plan left for it (the
  planner proved it unsolvable: a locked door in the way); every other order could;
- **the bar**: orders done / orders that could be done (issue 35: at least 95 %), and
  the latency, throughput and distance of the runs;
- every order not done, with its reason.

::

    python domains/robosim_hospital/measure.py --seeds 1-20 --orders steady,rush \\
        --events doors,icu_isolation --fail-rate 0.2 --jobs 2 --out /tmp/bar

With ``--out DIR`` each run's output is kept (``DIR/E-O-S.out``) and a run found there
is not run again. The tables are markdown.
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

FOLDER = Path(__file__).resolve().parent
FINAL = ("done", "failed", "refused", "cancelled")
#: What a reason says when no plan can reach an order's goal any more.
UNDOABLE = ("no robot can reach it", "unsolvable", "no plan exists", "cannot be reached")
ORDER_LINE = re.compile(r"^\[order\] (\S+) (\w+) at ([\d.]+) s(?:: (.*))?$")


@dataclass
class Run:
    """One run: each order's statuses in order, the reasons, the --json figures."""

    events: str
    orders: str
    seed: int
    statuses: dict[str, list[str]] = field(default_factory=dict)
    reasons: dict[str, str] = field(default_factory=dict)
    figures: dict[str, Any] = field(default_factory=dict)
    error: str = ""

    def final(self, order: str) -> str:
        finals = [s for s in self.statuses[order] if s in FINAL]
        return finals[-1] if finals else "lost"

    def could_not(self, order: str) -> bool:
        """Refused, or failed with no plan left: it could not be done."""
        status = self.final(order)
        reason = self.reasons.get(order, "")
        return status == "refused" or (
            status == "failed" and any(words in reason for words in UNDOABLE)
        )


def parse(events: str, orders: str, seed: int, stdout: str, stderr: str, code: int) -> Run:
    """A run from what ``plan-bridge run --json`` printed."""
    run = Run(events, orders, seed)
    for line in stderr.splitlines():
        found = ORDER_LINE.match(line.strip())
        if found is None:
            continue
        order, status, _, rest = found.groups()
        run.statuses.setdefault(order, []).append(status)
        if status in ("failed", "refused", "cancelled") and rest:
            run.reasons[order] = rest
    try:
        run.figures = json.loads(stdout.strip().splitlines()[-1]) if stdout.strip() else {}
    except json.JSONDecodeError:
        run.figures = {}
    if not run.figures.get("orders"):
        tail = [line for line in stderr.splitlines() if line.strip()][-1:] or [f"exit {code}"]
        run.error = tail[0]
    return run


def run_one(
    events: str, orders: str, seed: int, fail_rate: float, out: Path | None, binary: str
) -> Run:
    """One ``plan-bridge run`` (or its kept output in ``out``)."""
    kept = out / f"{events}-{orders}-{seed}.out" if out is not None else None
    if kept is not None and kept.is_file():
        data = json.loads(kept.read_text(encoding="utf-8"))
        return parse(events, orders, seed, data["stdout"], data["stderr"], data["code"])
    command = [binary, "run", str(FOLDER), "--orders", str(FOLDER / "orders" / f"{orders}.yaml")]
    command += ["--seed", str(seed), "--fail-rate", f"{fail_rate:g}", "--json"]
    if events:
        command += ["--events", str(FOLDER / "events" / f"{events}.yaml")]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if kept is not None:
        text = {"stdout": done.stdout, "stderr": done.stderr, "code": done.returncode}
        kept.write_text(json.dumps(text), encoding="utf-8")
    return parse(events, orders, seed, done.stdout, done.stderr, done.returncode)


def tally(runs: Sequence[Run]) -> dict[str, Any]:
    """The numbers of the runs of one (events, orders) pair."""
    count = dict.fromkeys(("arrived", *FINAL, "lost", "twice", "could_not"), 0)
    for run in runs:
        for order, statuses in run.statuses.items():
            count["arrived"] += 1
            count[run.final(order)] += 1
            count["twice"] += statuses.count("done") > 1
            count["could_not"] += run.could_not(order)
    doable = count["arrived"] - count["could_not"]

    def values(key: str) -> list[float]:
        found = [run.figures.get("orders", {}).get(key) for run in runs]
        return [float(v) for v in found if v is not None]

    distance = [float(r.figures["distance_m"]) for r in runs if "distance_m" in r.figures]
    return {
        **count,
        "runs": len(runs),
        "errors": sum(1 for r in runs if r.error),
        "doable": doable,
        "bar": count["done"] / doable if doable else 1.0,
        "latency_p50_s": _median(values("latency_p50_s")),
        "latency_p95_s": _median(values("latency_p95_s")),
        "orders_per_hour": _mean(values("orders_per_hour")),
        "distance_m": _mean(distance),
    }


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def _mean(values: list[float]) -> float | None:
    return statistics.fmean(values) if values else None


def _f(value: float | None, fmt: str) -> str:
    return "n/a" if value is None else format(value, fmt)


def report(runs: Sequence[Run]) -> str:
    """The table of every (events, orders) pair, then every order not done."""
    pairs = sorted({(r.events, r.orders) for r in runs})
    lines = [
        "| events | orders | runs | arrived | done | failed | refused | lost | done twice "
        "| could not be done | done / could be done | latency p50 (s) | latency p95 (s) "
        "| orders/h | distance (m) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for events, orders in pairs:
        t = tally([r for r in runs if (r.events, r.orders) == (events, orders)])
        lines.append(
            f"| {events or '-'} | {orders} | {t['runs']} | {t['arrived']} | {t['done']} | "
            f"{t['failed']} | {t['refused']} | {t['lost']} | {t['twice']} | {t['could_not']} | "
            f"{100 * t['bar']:.1f}% | {_f(t['latency_p50_s'], '.1f')} | "
            f"{_f(t['latency_p95_s'], '.1f')} | {_f(t['orders_per_hour'], '.1f')} | "
            f"{_f(t['distance_m'], '.0f')} |"
        )
    lines += ["", "Orders not done (events, orders, seed, order: status, reason):"]
    for run in runs:
        if run.error:
            lines.append(f"- {run.events} {run.orders} seed {run.seed}: the run broke: {run.error}")
        for order in run.statuses:
            status = run.final(order)
            if status != "done":
                why = "could not be done" if run.could_not(order) else "COULD have been done"
                reason = run.reasons.get(order, "")
                lines.append(
                    f"- {run.events} {run.orders} seed {run.seed}, {order}: {status} ({why}): "
                    f"{reason[:160]}"
                )
    return "\n".join(lines)


def _seeds(text: str) -> list[int]:
    seeds: list[int] = []
    for part in text.split(","):
        low, _, high = part.partition("-")
        seeds += list(range(int(low), int(high or low) + 1))
    return seeds


def main(argv: Iterable[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="1-20", help="e.g. 1-20 or 1,3,5 (default 1-20)")
    parser.add_argument("--orders", default="steady,rush", help="orders files (orders/NAME.yaml)")
    parser.add_argument(
        "--events", default="doors,icu_isolation", help="events files (events/NAME.yaml; - none)"
    )
    parser.add_argument("--fail-rate", type=float, default=0.2)
    parser.add_argument("--jobs", type=int, default=2, help="runs at once (default 2)")
    parser.add_argument("--out", type=Path, help="keep each run's output here (and reuse it)")
    args = parser.parse_args(None if argv is None else list(argv))
    binary = str(Path(sys.executable).with_name("plan-bridge"))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
    work = [
        (events if events != "-" else "", orders, seed)
        for events in args.events.split(",")
        for orders in args.orders.split(",")
        for seed in _seeds(args.seeds)
    ]

    def one(item: tuple[str, str, int]) -> Run:
        return run_one(*item, args.fail_rate, args.out, binary)

    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        runs = list(pool.map(one, work))
    print(report(runs))
    return 1 if any(r.error for r in runs) else 0


if __name__ == "__main__":
    sys.exit(main())
