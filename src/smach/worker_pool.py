"""A grow-on-demand pool of daemon threads that run Concurrence children.

Nested Concurrences need as many threads as there are children running at once, so
the pool never caps its size (a fixed cap would deadlock nested containers). Idle
workers are kept for reuse and exit after ``IDLE_SECONDS`` without work. A task that
no worker has started yet can be cancelled: Concurrence cancels the helper it
queued when the calling thread ran every child itself.
"""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable

__all__ = ["cancel", "size", "submit"]

IDLE_SECONDS = 30.0

Task = Callable[[], None]

_cond = threading.Condition(threading.Lock())
_queue: collections.deque[Task] = collections.deque()
_idle = 0
_count = 0


def _worker() -> None:
    global _idle, _count
    while True:
        with _cond:
            _idle += 1
            while not _queue:
                if not _cond.wait(IDLE_SECONDS) and not _queue:
                    _idle -= 1
                    _count -= 1
                    return
            task = _queue.popleft()
            _idle -= 1
        task()


def submit(task: Task) -> None:
    """Run ``task`` on a pool thread (the task must handle its own exceptions).

    Submitting the same callable object twice queues it twice; :func:`cancel` removes
    one queued occurrence.
    """
    global _count
    with _cond:
        _queue.append(task)
        spawn = _idle < len(_queue)
        if spawn:
            _count += 1
            number = _count
        else:
            _cond.notify()
    if spawn:
        threading.Thread(target=_worker, name=f"smach-worker-{number}", daemon=True).start()


def cancel(task: Task) -> bool:
    """Remove ``task`` if no worker has started it; True if it was removed."""
    with _cond:
        try:
            _queue.remove(task)
        except ValueError:
            return False
        return True


def size() -> int:
    """Number of worker threads alive (busy or idle)."""
    return _count
