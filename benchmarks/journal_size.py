"""Journal size per action, structure copies, and replay load time of a long mission.

    .venv/bin/python benchmarks/journal_size.py [--seeds 4] [--steps 2000]

1. Every shipped mission (domains/*) with seeds 0..N-1 at fail rate 0.2, journaled by
   ``plan-bridge run --journal``: bytes per executed action, how many ``structure``
   records, and the shares of structures and checkpoints in the file.
2. A 2000-step plan (a robot walking a line, a fixed planner, 1 % of the moves fail
   and are replanned) journaled as ``plan-bridge run`` does (events, a checkpoint
   after every step with the world's snapshot): bytes per action, and the time to
   load it for replay (read, fold every record into the viewer's history, the view
   in the middle and its SVG).

Runs in this checkout; ``PYTHONPATH=OTHER/src`` measures another one (part 2 then
writes whole checkpoints if that checkout has no ``Journal.write_state``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from domain_folders import mission_folders


def sizes(path: Path) -> dict[str, int]:
    out: dict[str, int] = {"bytes": 0, "structure": 0, "structures": 0, "checkpoint": 0}
    with path.open("rb") as f:
        for line in f:
            out["bytes"] += len(line)
            head = line[:30]
            if b'"kind": "structure"' in head:
                out["structure"] += len(line)
                out["structures"] += 1
            elif b'"kind": "checkpoint"' in head:
                out["checkpoint"] += len(line)
    return out


def missions(domains: Path, seeds: int, tmp: Path) -> None:
    print("1. shipped missions, fail rate 0.2")
    total_bytes = total_actions = total_structures = total_plans = 0
    for domain in mission_folders(domains):
        for seed in range(seeds):
            journal = tmp / f"{domain}-{seed}.jsonl"
            result = subprocess.run(
                [sys.executable, "-m", "plan_bridge", "run", str(domains / domain), "--seed",
                 str(seed), "--fail-rate", "0.2", "--journal", str(journal), "--quiet", "--json"],
                capture_output=True, text=True, timeout=300, check=False,
                env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
            )  # fmt: skip
            report = json.loads(result.stdout)
            s = sizes(journal)
            actions = max(1, report["actions_executed"])
            plans = report["planner_calls"]
            total_bytes += s["bytes"]
            total_actions += actions
            total_structures += s["structures"]
            total_plans += plans
            print(
                f"   {domain:19s} seed {seed}: {actions:3d} actions, {s['bytes'] / 1024:6.1f} KB, "
                f"{s['bytes'] / actions / 1024:5.1f} KB/action; {s['structures']} structure "
                f"records ({s['structure'] / s['bytes']:4.0%}), checkpoints "
                f"{s['checkpoint'] / s['bytes']:4.0%}; {plans} planner calls"
            )
    print(
        f"   all: {total_bytes / total_actions / 1024:.1f} KB per action; {total_structures} "
        f"structure records for {total_plans} planner calls"
    )


def long_mission(steps: int, tmp: Path) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    from load_soak import FixedPlanner, chain_task

    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
    from smach.introspection.journal import Journal, read_journal
    from smach.introspection.model import History
    from smach.introspection.structure import StateNode
    from smach.introspection.svg import render_svg

    task = chain_task(steps)
    world = SimulatedWorld(task, seed=1, fail_rate=0.01)
    executive = Executive(
        task, symbolic_skills(world), FixedPlanner(steps),  # type: ignore[arg-type]
        policy=ReplanPolicy(max_replans=1000),
    )  # fmt: skip
    path = tmp / "long.jsonl"
    journal = Journal(path, executive)
    whole = not hasattr(journal, "write_state")

    def checkpoint(state: dict[str, Any]) -> None:
        if whole:
            journal.write_raw("checkpoint", state=state, world=world.snapshot())
        else:
            journal.write_state("checkpoint", state=state, world=world.snapshot())

    executive.checkpoint = checkpoint
    started = time.perf_counter()
    outcome = executive.execute()
    journal.close()
    run_s = time.perf_counter() - started
    s = sizes(path)
    actions = executive.report.actions_executed
    print(f"2. a {steps}-step plan, 1 % of the moves fail ({outcome}, {run_s:.1f} s)")
    print(
        f"   {actions} actions, {executive.report.replans} replans: {s['bytes'] / 2**20:.1f} MB, "
        f"{s['bytes'] / actions / 1024:.2f} KB/action; {s['structures']} structure records "
        f"({s['structure'] / s['bytes']:.0%}), checkpoints {s['checkpoint'] / s['bytes']:.0%}"
    )
    started = time.perf_counter()
    header, records = read_journal(path)
    history = History(header, limit=len(records) + 1)
    for record in records:
        history.add(record)
    view = history.view_at(len(records) // 2)
    folded_s = time.perf_counter() - started
    root = StateNode.from_dict(view.structure or {})
    started = time.perf_counter()
    render_svg(root, collapsed=())
    full_s = time.perf_counter() - started
    print(
        f"   replay load: read and fold {len(records)} records {folded_s:.2f} s; "
        f"SVG of the whole tree {full_s:.2f} s"
    )
    try:
        from smach.introspection.layout import off_path
    except ImportError:
        return
    started = time.perf_counter()
    render_svg(root, collapsed=off_path(root, list(view.active)))
    print(f"   SVG of the page's default (Focus) view: {time.perf_counter() - started:.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--domains", default=str(Path(__file__).parents[1] / "domains"))
    parser.add_argument("--only-long", action="store_true", help="part 2 only")
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if not options.only_long:
            missions(Path(options.domains), options.seeds, Path(tmp))
        long_mission(options.steps, Path(tmp))


if __name__ == "__main__":
    main()
