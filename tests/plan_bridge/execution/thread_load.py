"""A busy thread beside a test: the tests of repeatability run under it."""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def busy_thread(switch_interval: float = 1e-6) -> Iterator[None]:
    """A thread spinning beside the test, with thread switches every
    ``switch_interval`` seconds: the other threads run in whatever order the
    scheduler picks."""
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            pass

    interval = sys.getswitchinterval()
    sys.setswitchinterval(switch_interval)
    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    try:
        yield
    finally:
        stop.set()
        spinner.join()
        sys.setswitchinterval(interval)
