"""A mission of orders killed at any moment resumes and accounts for every order once."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from smach.introspection.journal import read_journal

COURIERS = Path(__file__).parents[1] / "data" / "couriers"
RUN = ("--orders", str(COURIERS / "orders.yaml"), "--fail-rate", "0.2", "--seed", "4")

pytestmark = pytest.mark.timeout(300)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "plan_bridge", *args]


def _statuses(journal: Path) -> dict[str, str]:
    """Each order's last status in the journal."""
    _, records = read_journal(journal)
    return {r["order"]: r["status"] for r in records if r["kind"] == "order"}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    journal = tmp_path_factory.mktemp("whole") / "run.jsonl"
    result = subprocess.run(
        _cli("run", str(COURIERS), *RUN, "--journal", str(journal), "--quiet", "--json"),
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert result.returncode == 0, result.stderr
    return {"figures": json.loads(result.stdout), "statuses": _statuses(journal)}


@pytest.mark.parametrize("lines", [40, 150, 400])
def test_a_killed_mission_of_orders_resumes_with_the_same_orders_done(
    tmp_path: Path, lines: int, uninterrupted: dict[str, Any]
) -> None:
    journal = tmp_path / "run.jsonl"
    process = subprocess.Popen(
        _cli("run", str(COURIERS), *RUN, "--journal", str(journal), "--quiet"),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    while process.poll() is None and time.monotonic() < deadline:
        if journal.exists() and journal.read_bytes().count(b"\n") >= lines:
            os.kill(process.pid, signal.SIGKILL)
            break
        time.sleep(0.002)
    process.wait(30)
    if process.returncode != -signal.SIGKILL or b'"kind": "summary"' in journal.read_bytes():
        pytest.skip("the run finished before the kill point")

    resumed = subprocess.run(
        _cli("run", "--resume", str(journal), "--quiet", "--json"),
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert resumed.returncode == 0, resumed.stderr
    figures = json.loads(resumed.stdout)
    assert _statuses(journal) == uninterrupted["statuses"]
    whole = uninterrupted["figures"]["orders"]
    for key in ("orders", "done", "refused", "failed", "cancelled", "not_arrived"):
        assert figures["orders"][key] == whole[key], key
