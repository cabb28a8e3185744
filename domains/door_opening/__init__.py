"""door_opening: reach a goal room through doors, some of them locked.

The mission protocol of ``plan-bridge run domains/door_opening``: :func:`setup` gives
the planned mission's skills and simulated world, :func:`scripted` the hand-written
baseline. See README.md.
"""

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
