"""Time of the PDDL front end on a 14 MB problem (200,000 objects, 600,000 facts).

    .venv/bin/python benchmarks/front_end_size.py

Prints wall-clock and CPU seconds of the cheap checks (check_source) and of the
positioned pass (analyse), without unified-planning.
"""

from __future__ import annotations

import time
from pathlib import Path

from plan_bridge.pddl.front_end import analyse
from plan_bridge.pddl.source import check_source, decode_source

CORPUS = Path(__file__).resolve().parents[1] / "tests/plan_bridge/pddl/corpus/base"


def main() -> None:
    domain = (CORPUS / "domain.pddl").read_text()
    problem = (CORPUS / "problem.pddl").read_text()
    objects = "".join(f" p{i}" for i in range(200_000))
    facts = "".join(f"(link p{i} p{i + 1})" for i in range(199_999)) * 3
    problem = problem.replace("depot shop - place", "depot shop" + objects + " - place")
    problem = problem.replace("(link shop depot))", "(link shop depot)" + facts + ")")
    domain_source = decode_source(domain.encode(), "domain.pddl", "domain")
    problem_source = decode_source(problem.encode(), "problem.pddl", "problem")
    wall, cpu = time.perf_counter(), time.process_time()
    check_source(domain_source)
    check_source(problem_source, max_bytes=20_000_000)
    checked = time.perf_counter() - wall, time.process_time() - cpu
    front = analyse(domain_source, problem_source)
    total = time.perf_counter() - wall, time.process_time() - cpu
    print(f"problem: {len(problem) / 1e6:.1f} MB, {len(front.problem_model.objects)} objects")
    print(f"check_source: {checked[0]:.2f} s wall, {checked[1]:.2f} s CPU")
    print(f"check_source + analyse: {total[0]:.2f} s wall, {total[1]:.2f} s CPU")


if __name__ == "__main__":
    main()
