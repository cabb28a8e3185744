"""fetch_drink: fetch a drink from the refrigerator and hand it to a person.

The mission protocol of ``plan-bridge run domains/fetch_drink``: :func:`setup` gives
the planned mission's skills and simulated world, :func:`scripted` the hand-written
baseline. See README.md.
"""

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
