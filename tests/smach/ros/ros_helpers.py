"""Helpers for the smach.ros tests (waiting, reading server output)."""

from __future__ import annotations

import subprocess
import threading
import time
from typing import Any


def wait_for(predicate: Any, timeout: float = 10.0, period: float = 0.02) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(period)
    return bool(predicate())


def read_lines(process: subprocess.Popen[str]) -> list[str]:
    """Collect the server's stdout lines in the background; returns the live list."""
    lines: list[str] = []

    def pump() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.append(line.strip())

    threading.Thread(target=pump, daemon=True).start()
    return lines
