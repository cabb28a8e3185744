"""How many broken PDDL files of the front end's corpus get an error at the defect's line.

    .venv/bin/python benchmarks/front_end_corpus.py [CORPUS]

Reads tests/plan_bridge/pddl/corpus (each file states its expected verdict and line),
runs what `plan-bridge check/plan/run` run on the input (the front end, then
unified-planning's reader) and prints, for the broken files, how many errors name
the right file and line, and how long the whole verdict took. Runs against whatever
plan_bridge is importable, so an older checkout can be measured with PYTHONPATH.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.task import load_task

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "plan_bridge" / "pddl"))
from corpus_cases import CORPUS as DEFAULT_CORPUS  # noqa: E402
from corpus_cases import expectations, pair  # noqa: E402

CORPUS = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_CORPUS


def verdict(domain: Path, problem: Path) -> None:
    try:
        from plan_bridge.cli.base import check_input
    except ImportError:  # before the front end: the CLI only had the cheap checks
        from plan_bridge.pddl.source import check_source, read_source

        check_source(read_source(domain, "domain"))
        check_source(read_source(problem, "problem"))
    else:
        check_input(domain, problem)
    load_task(domain, problem)


def main() -> None:
    broken = located = right_file = accepted = valid = 0
    misses: list[str] = []
    started = time.perf_counter()
    for path in sorted(CORPUS.glob("*.pddl")):
        meta = expectations(path)
        domain, problem = pair(path, meta)
        error: PlanBridgeError | None = None
        try:
            verdict(domain, problem)
        except PlanBridgeError as exc:
            error = exc
        if meta["verdict"] != "error":
            valid += 1
            accepted += error is None
            continue
        if meta.get("unless-installed"):
            continue  # its verdict depends on the installed engines
        broken += 1
        expected_file = domain if meta["where"] == "domain" else problem
        line = getattr(error, "line", None)
        path_ok = getattr(error, "path", None) == str(expected_file)
        right_file += path_ok
        want = None if meta["line"] == "none" else int(meta["line"])
        if error is not None and path_ok and line == want:
            located += 1
        else:
            misses.append(
                f"  {path.name}: expected line {want}, got {line if error else 'no error'}"
            )
    elapsed = time.perf_counter() - started
    print(
        f"broken files: {broken}; error at the defect's file and line: {located}; right file: {right_file}"
    )
    print(f"odd-but-valid files: {valid}; accepted: {accepted}")
    print(f"total time for {broken + valid} verdicts: {elapsed:.1f} s")
    if misses:
        print("missed:\n" + "\n".join(misses))


if __name__ == "__main__":
    main()
