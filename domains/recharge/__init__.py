"""recharge: deliver items between rooms; recharge when the battery monitor fires.

The mission protocol of ``plan-bridge run domains/recharge``: :func:`setup` gives the
planned mission's skills and simulated world, :func:`scripted` the hand-written
baseline. See README.md.
"""

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
