"""One shared timer thread for deadlines (Timeout containers, ROS state watchdogs).

A thread per deadline would cost ~100 µs per execution; a heap served by a single
daemon thread costs a lock and a heap push. Callbacks run on the timer thread and
must be short (they typically just call ``request_preempt()``).
"""

from __future__ import annotations

import heapq
import itertools
import threading
import time
from collections.abc import Callable

from smach.log import loggers

__all__ = ["TimerHandle", "schedule"]


class TimerHandle:
    """A scheduled callback; :meth:`cancel` stops it if it has not fired yet."""

    __slots__ = ("callback", "cancelled", "deadline", "fired")

    def __init__(self, deadline: float, callback: Callable[[], object]) -> None:
        self.deadline = deadline
        self.callback = callback
        self.cancelled = False
        self.fired = False

    def cancel(self) -> bool:
        """Cancel; True if the callback had not run (and now never will)."""
        with _cond:
            if self.fired:
                return False
            self.cancelled = True
            return True


_cond = threading.Condition(threading.Lock())
_heap: list[tuple[float, int, TimerHandle]] = []
_seq = itertools.count()
_thread: threading.Thread | None = None


def _serve() -> None:
    while True:
        with _cond:
            while True:
                while _heap and _heap[0][2].cancelled:
                    heapq.heappop(_heap)
                now = time.monotonic()
                if _heap and _heap[0][0] <= now:
                    handle = heapq.heappop(_heap)[2]
                    handle.fired = True
                    break
                _cond.wait(None if not _heap else _heap[0][0] - now)
        try:
            handle.callback()
        except Exception as exc:  # a timer callback must never kill the timer thread
            loggers.logerr(f"timer callback {handle.callback!r} raised {exc!r}")


def schedule(delay: float, callback: Callable[[], object]) -> TimerHandle:
    """Call ``callback()`` on the timer thread after ``delay`` seconds."""
    global _thread
    handle = TimerHandle(time.monotonic() + max(0.0, delay), callback)
    with _cond:
        if _thread is None:
            _thread = threading.Thread(target=_serve, name="smach-timers", daemon=True)
            _thread.start()
        heapq.heappush(_heap, (handle.deadline, next(_seq), handle))
        _cond.notify()
    return handle
