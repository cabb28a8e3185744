"""Waiting for what another thread or process does, with a deadline.

What a robot process prints, what a ROS callback or a writer thread records, comes
when that thread gets to run: on a busy machine, later than the call that caused it
returns. A test asserts on it through :func:`wait_until`, which polls until the
condition holds or the deadline passes (then the assertion fails with what was seen).
"""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["wait_until"]


def wait_until(
    predicate: Callable[[], object], timeout: float = 10.0, period: float = 0.01
) -> bool:
    """Whether ``predicate()`` became true within ``timeout`` seconds (polled every
    ``period``; tried once more at the deadline)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(period)
    return bool(predicate())
