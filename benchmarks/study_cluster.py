"""Wall time of one study run locally and on local Dask clusters of 1, 2 and 4 workers.

    .venv/bin/python benchmarks/study_cluster.py [--runs 5] [--workers 1,2,4] [--keep DIR]
        [--targets T1,T2] [--approaches A,B] [--fault-rates R,S]

Runs ``plan-bridge study domains/fetch_drink domains/door_opening --runs N`` (every
approach, fault rates 0,0.1,0.2,0.4) once with ``--jobs 1``, once with ``--jobs 2``
and once per ``--cluster local:W``, each into a fresh folder, and prints the wall
time of each and its speed-up over ``--jobs 1``. It also checks that every cluster
study wrote the same rows as the local one (timing and host/worker columns aside).
Needs ``pip install -e '.[cluster]'``. Opt-in: not part of the test suite.
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGETS = ["domains/fetch_drink", "domains/door_opening"]
VARYING = {"wall_time_s", "planning_time_s", "host", "worker"}


def rows_of(folder: Path) -> dict[tuple[str, ...], dict[str, str]]:
    with (folder / "results.csv").open(newline="") as f:
        return {
            (r["target"], r["approach"], r["fault_rate"], r["seed"]): {
                k: v for k, v in r.items() if k not in VARYING
            }
            for r in csv.DictReader(f)
        }


def study(targets: list[str], args: list[str], out: Path) -> float:
    plan_bridge = Path(sys.executable).with_name("plan-bridge")
    command = [str(plan_bridge), "study", *targets, *args, "--out", str(out)]
    print("$", " ".join(command[1:]).replace(str(out), "OUT"), flush=True)
    started = time.monotonic()
    subprocess.run(
        command,
        cwd=ROOT,
        check=True,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
    )
    return time.monotonic() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workers", default="1,2,4")
    parser.add_argument("--keep", help="keep the study folders under this directory")
    parser.add_argument("--targets", default=",".join(TARGETS))
    parser.add_argument("--approaches", help="default: the study's default (every approach)")
    parser.add_argument("--fault-rates", help="default: the study's default")
    args = parser.parse_args()
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="study-bench-"))
    targets = args.targets.split(",")
    common = ["--runs", str(args.runs)]
    if args.approaches:
        common += ["--approaches", args.approaches]
    if args.fault_rates:
        common += ["--fault-rates", args.fault_rates]
    results: list[tuple[str, float]] = []
    for jobs in (1, 2):
        results.append(
            (f"--jobs {jobs}", study(targets, [*common, "--jobs", str(jobs)], base / f"j{jobs}"))
        )
    reference = rows_of(base / "j1")
    for workers in (int(w) for w in args.workers.split(",")):
        folder = base / f"c{workers}"
        seconds = study(targets, [*common, "--cluster", f"local:{workers}"], folder)
        results.append((f"--cluster local:{workers}", seconds))
        if rows_of(folder) != reference:
            raise SystemExit(f"local:{workers} wrote other rows than --jobs 1 (see {folder})")
    print(
        f"\n{len(reference)} runs per study; {os.cpu_count()} CPUs "
        f"({platform.processor() or platform.machine()}); rows identical across executors"
    )
    print("| executor | wall time (s) | speed-up vs --jobs 1 |")
    print("|---|---:|---:|")
    for name, seconds in results:
        print(f"| `{name}` | {seconds:.1f} | x{results[0][1] / seconds:.2f} |")


if __name__ == "__main__":
    main()
