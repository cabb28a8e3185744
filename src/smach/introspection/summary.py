"""Bounded, JSON-safe summaries of values: moved to the core, :mod:`smach.summary`.

Re-exported here, where journals, viewers and user code have always imported them.
"""

from __future__ import annotations

from smach.summary import (
    MAX_DEPTH,
    MAX_ITEMS,
    MAX_REPR,
    PLAIN,
    Summary,
    frozen,
    short_repr,
    summarise,
)

__all__ = [
    "MAX_DEPTH",
    "MAX_ITEMS",
    "MAX_REPR",
    "PLAIN",
    "Summary",
    "frozen",
    "short_repr",
    "summarise",
]
