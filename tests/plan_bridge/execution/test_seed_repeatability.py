"""A seeded simulated run is a function of its seed, whatever the threads do.

Each mission is run a few times in this process while a thread spins beside it and
Python switches threads as often as it can: the temporal dispatcher's step threads and
the Concurrence layers' threads are scheduled differently every time, and the runs must
still agree on every step, decision, outcome and fault. (Before the simulated clock,
timed_courier p01 seed 4 and p02 seed 2 gave different decisions from run to run.)
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

import pytest
from thread_load import busy_thread

from plan_bridge.cli import main

pytestmark = pytest.mark.timeout(300)

DOMAINS = Path(__file__).resolve().parents[3] / "domains"
COMPARED = ("executed", "decisions", "outcome", "goal_reached", "faults_injected", "actions_failed")


def run(*argv: str) -> dict[str, Any]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        main(["run", *argv, "--fail-rate", "0.3", "--time-scale", "0", "--json", "--quiet"])
    data: dict[str, Any] = json.loads(out.getvalue())
    return {key: data[key] for key in (*COMPARED, "sim_time_s")}


@pytest.mark.parametrize(
    "argv",
    [
        (str(DOMAINS / "timed_courier"), "--problem", "p01", "--seed", "4"),
        (str(DOMAINS / "two_robot_delivery"), "--concurrent", "--seed", "3"),
    ],
    ids=["timed_courier-p01-seed4", "two_robot_delivery-concurrent-seed3"],
)
def test_a_seeded_run_repeats_exactly_with_a_busy_thread_beside_it(argv: tuple[str, ...]) -> None:
    first = run(*argv)
    assert first["executed"] and first["faults_injected"] > 0  # faults met, steps run
    assert first["sim_time_s"] > 0  # the world's clock moved
    with busy_thread(1e-5):
        again = [run(*argv) for _ in range(3)]
    for other in again:
        assert other == first
