"""Our `plan-bridge check` verdict against unified-planning's reader on every IPC pair.

    .venv/bin/python tools/ipc_corpus_agreement.py [--mode full|front-end] [--jobs N]
                                                   [--limit S] [--corpus DIR] [--list]

For each domain/problem pair of the IPC corpus (``../shared/pddl-corpus``: one domain
and its first problem per IPC domain variant 1998-2014), in worker processes with a
time limit per pair: UP's reader alone on the files, and what `check` runs before
planning (the front end, then UP's reader on the rewritten text). Prints how many
pairs UP reads, how many we accept, refuse as an error and refuse as unsupported,
the warnings we give, the slowest pairs, and one line per disagreement: a pair UP
reads that we refuse, a traceback, a hang. Exits 1 when there is any.

``--mode front-end`` runs the front end alone, and UP's reader only on the pairs the
front end refuses (what the CI test does, in seconds). Runs against whatever
plan_bridge is importable, so an older checkout can be measured with PYTHONPATH
(its front end must have ``plan_bridge.cli.base.check_input``). The same comparison
is the test ``test_check_accepts_every_ipc_pair_that_unified_planning_reads``
(``PLAN_BRIDGE_IPC_FULL=1``).
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "plan_bridge" / "pddl"))
from ipc_corpus import (  # noqa: E402
    ACCEPTS,
    ERROR,
    IPC_CORPUS,
    READS,
    REFUSES,
    UNSUPPORTED,
    Verdict,
    disagreements,
    ipc_pairs,
    judge_pairs,
)


def _kind(warning: str) -> str:
    """A warning without its location and particulars, to count them by kind."""
    text = re.sub(r"^.*?:\d+:\d+: ", "", warning)
    for marker in (
        "no initial value",
        "a duration of 0",
        "is already a constant of the domain",
        "has the name of",
        "(in-package ...)",
        "the goal is empty",
    ):
        if marker in text:
            return marker
    match = re.match(r"uses (:[\w-]+)", text)
    return f"uses {match.group(1)} undeclared" if match else text[:60]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--mode", choices=["full", "front-end"], default="full")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--limit", type=float, default=600.0, help="seconds per pair")
    parser.add_argument("--corpus", type=Path, default=IPC_CORPUS)
    parser.add_argument("--list", action="store_true", help="print every pair's verdict")
    args = parser.parse_args()
    pairs = ipc_pairs(args.corpus)
    if not pairs:
        print(f"no IPC corpus in {args.corpus}", file=sys.stderr)
        return 2
    started = time.perf_counter()
    verdicts: list[Verdict] = []
    for verdict in judge_pairs(pairs, mode=args.mode, limit=args.limit, jobs=args.jobs):
        verdicts.append(verdict)
        if args.list:
            print(f"{verdict.pair.name}: UP {verdict.up or '-'}, we {verdict.ours}", flush=True)
    wall = time.perf_counter() - started
    verdicts.sort(key=lambda v: v.pair.name)

    ours = collections.Counter(v.ours for v in verdicts)
    print(f"{len(verdicts)} pairs ({args.mode}, {args.jobs} jobs, {wall:.0f} s wall-clock)")
    if args.mode == "full":
        read = [v for v in verdicts if v.up == READS]
        print(f"  unified-planning's reader reads {len(read)}, refuses {len(verdicts) - len(read)}")
        print(
            f"  we accept {ours[ACCEPTS]} ({sum(v.ours == ACCEPTS for v in read)} of the "
            f"{len(read)} UP reads, {sum(v.ours == ACCEPTS and v.up == REFUSES for v in verdicts)} "
            "that it refuses)"
        )
    else:
        print(f"  the front end accepts {ours[ACCEPTS]}")
    print(f"  we refuse {ours[UNSUPPORTED]} as unsupported, {ours[ERROR]} as errors")
    for verdict in verdicts:
        if verdict.ours in (ERROR, UNSUPPORTED):
            print(f"    {verdict.pair.name}: {verdict.message[:150]}")
    kinds = collections.Counter(_kind(w) for v in verdicts for w in v.warnings)
    pairs_with = collections.Counter(
        kind for v in verdicts for kind in {_kind(w) for w in v.warnings}
    )
    print("  warnings (count, pairs):")
    for kind, count in kinds.most_common():
        print(f"    {count:4d} {pairs_with[kind]:4d}  {kind}")
    print("  slowest pairs (ours + UP alone):")
    for verdict in sorted(verdicts, key=lambda v: -(v.seconds + v.up_seconds))[:5]:
        print(f"    {verdict.seconds + verdict.up_seconds:6.2f} s  {verdict.pair.name}")
    problems = disagreements(verdicts)
    print(f"{len(problems)} disagreement(s)")
    for problem in problems:
        print(f"  {problem}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
