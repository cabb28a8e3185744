"""Large stress run of random nested machines (issue: no hangs, no leaks).

Usage: python benchmarks/stress.py [--runs 5000] [--seed 0] [--depth 4]
Prints the number of runs, outcomes, smach errors, preempts sent, hangs (must be 0),
unexpected results (must be none) and the longest run.
"""

from __future__ import annotations

import argparse
import logging
import sys
import threading
import time

from smach import worker_pool
from smach.stress import stress


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--depth", type=int, default=4)
    args = parser.parse_args()
    logging.getLogger("smach").setLevel(logging.ERROR)  # unserviced-preempt warnings are expected
    started = time.monotonic()
    report = stress(args.runs, args.seed, max_depth=args.depth)
    elapsed = time.monotonic() - started
    print(f"runs: {report.runs} in {elapsed:.1f} s (depth <= {args.depth}, seed {args.seed})")
    print(f"outcomes: {report.outcomes}; smach errors: {report.errors}")
    print(
        f"preempts sent: {report.preempts_sent}; hangs: {report.hung}; longest run: {report.max_seconds:.3f} s"
    )
    print(f"unexpected: {report.unexpected[:5] or 'none'}")
    print(f"threads alive after: {threading.active_count()} (pool workers: {worker_pool.size()})")
    return 0 if report.hung == 0 and not report.unexpected else 1


if __name__ == "__main__":
    sys.exit(main())
