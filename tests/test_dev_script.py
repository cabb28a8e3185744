"""`./dev`'s first set-up says what pip is doing: a line when pip's latest line changes
(looked at every 5 s), not the same line again every 5 s (a first `./dev run` printed
"Installing collected packages" 16 times). Its `watch_pip` runs against a fake pip
that writes a log slowly; nothing is installed."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def watch(tmp_path: Path, script: str) -> list[str]:
    """The lines `watch_pip` prints while a fake pip runs ``script`` (bash) on its log."""
    dev = (ROOT / "dev").read_text()
    function = re.search(r"^watch_pip\(\) \{\n.*?^\}\n", dev, re.S | re.M)
    assert function is not None, "dev has no watch_pip function"
    log = tmp_path / "install.log"
    log.write_text("")
    program = (
        "set -euo pipefail\n"
        + function.group(0)
        + f"( {script} ) >>{log} &\n"
        + f"watch_pip $! {log}\n"
    )
    done = subprocess.run(
        ["bash", "-c", program], capture_output=True, text=True, timeout=60, check=True
    )
    return done.stderr.splitlines()


@pytest.mark.timeout(60)
def test_dev_prints_what_pip_does_only_when_it_changes(tmp_path: Path) -> None:
    lines = watch(
        tmp_path,
        "echo 'Collecting unified-planning'; sleep 7; "
        "echo 'Installing collected packages: unified-planning, smach-planner'; sleep 9",
    )
    assert lines == [
        "[dev] 5s: Collecting unified-planning",
        "[dev] 10s: Installing collected packages: unified-planning, smach-planner",
    ]  # not again at 15 s
