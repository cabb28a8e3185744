"""Does a resumed run end as the uninterrupted one? Kill points drawn at random.

For each of N kill points: a mission (domain folder, seed) is run to the end with
``--journal``; a copy of its journal is cut at a random byte (as a process killed at
that moment leaves it, torn last line included), resumed with ``--resume``, and the
end of the resumed run is compared with the uninterrupted one: goal reached, the
steps executed (as a multiset: steps of two robots that ran concurrently have no
order between them), the faults injected and the simulated time.

    .venv/bin/python benchmarks/resume_fidelity.py --kills 32 [--seed 0]

Runs ``python -m plan_bridge`` in subprocesses, so ``PYTHONPATH=OTHER/src`` measures
another checkout the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from domain_folders import mission_folders

COMPARED = ("goal_reached", "executed", "faults_injected", "sim_time_s")


def run(args: list[str]) -> dict[str, Any]:
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    result = subprocess.run(
        [sys.executable, "-m", "plan_bridge", "run", *args, "--quiet", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env=env,
    )
    if not result.stdout.strip():
        return {"error": result.stderr.strip().splitlines()[-1:]}
    data: dict[str, Any] = json.loads(result.stdout)
    return data


def end_of(report: dict[str, Any]) -> dict[str, Any]:
    end = {key: report.get(key) for key in COMPARED}
    # Steps of two robots that ran concurrently have no order between them.
    end["executed"] = sorted(end["executed"] or [])
    return end


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kills", type=int, default=32)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--domains", default=str(Path(__file__).parents[1] / "domains"))
    parser.add_argument("--fail-rate", default="0.3")
    options = parser.parse_args()
    rng = random.Random(options.seed)
    missions = mission_folders(Path(options.domains))
    same = 0
    different: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        baselines: dict[tuple[str, int], tuple[dict[str, Any], bytes]] = {}
        for n in range(options.kills):
            domain, mission_seed = rng.choice(missions), rng.randrange(4)
            key = (domain, mission_seed)
            if key not in baselines:
                journal = Path(tmp) / f"{domain}-{mission_seed}.jsonl"
                report = run([f"{options.domains}/{domain}", "--seed", str(mission_seed),
                              "--fail-rate", options.fail_rate, "--journal", str(journal)])  # fmt: skip
                baselines[key] = (report, journal.read_bytes())
            report, data = baselines[key]
            first_line = data.index(b"\n") + 1
            last_summary = data.rfind(b'{"kind": "summary"')
            cut = rng.randrange(first_line, last_summary)
            killed = Path(tmp) / f"kill-{n}.jsonl"
            killed.write_bytes(data[:cut])
            resumed = run(["--resume", str(killed)])
            if end_of(resumed) == end_of(report):
                same += 1
            else:
                diff = {
                    k: (end_of(report)[k], end_of(resumed).get(k))
                    for k in COMPARED
                    if end_of(report)[k] != end_of(resumed).get(k)
                }
                different.append(f"{domain} seed {mission_seed} cut at byte {cut}: {diff}")
    print(f"resume ends as the uninterrupted run: {same}/{options.kills}")
    for line in different:
        print(f"  differs: {line}"[:400])


if __name__ == "__main__":
    main()
