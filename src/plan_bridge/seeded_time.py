"""Times of a run given as seconds or as a window drawn from the run's seed.

World events (:mod:`plan_bridge.robosim.events`) and orders
(:mod:`plan_bridge.orders.order_file`) say when they happen as ``at: SECONDS`` or
``at: [LO, HI]``: a window's time is drawn uniformly, once per run, from the run's
seed and a key (what shares a key shares the time), so a seeded run repeats and other
seeds see other moments.
"""

from __future__ import annotations

import math
import random
from typing import Any

__all__ = ["draw_time", "is_seconds", "read_time"]


def is_seconds(value: Any) -> bool:
    """Whether ``value`` is a finite number of seconds, 0 or more (not a bool)."""
    return (
        not isinstance(value, bool)
        and isinstance(value, (int, float))
        and math.isfinite(value)
        and value >= 0
    )


def read_time(at: Any) -> tuple[float, tuple[float, float] | None] | str:
    """``at:`` as (seconds, window): a number (no window) or ``[LO, HI]`` (the time is
    ``LO`` until drawn); else what is wrong with it, as text for the caller's error."""
    if is_seconds(at):
        return float(at), None
    if isinstance(at, list) and len(at) == 2 and all(is_seconds(v) for v in at):
        low, high = float(at[0]), float(at[1])
        if low > high:
            return f"at: [{at[0]}, {at[1]}]: the window's start is after its end"
        return low, (low, high)
    return f"at: must be seconds >= 0 or a window [LO, HI] of them, got {at!r}"


def draw_time(window: tuple[float, float], seed: int, key: str) -> float:
    """The time of ``window`` in a run with ``seed``: uniform in it, the same for every
    draw with the same seed and key (ms resolution)."""
    low, high = window
    return round(random.Random(f"{key}:{seed}:{low!r}:{high!r}").uniform(low, high), 3)
