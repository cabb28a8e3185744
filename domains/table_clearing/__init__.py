"""Table clearing: clear N objects from a table onto a cart, push the cart to the kitchen.

``plan-bridge run domains/table_clearing`` plans the mission with a PDDL planner and
runs every plan step as a hand-written SMACH skill (skills.py) in a simulated world
with seeded faults (world.py); ``scripted`` is the same mission as one hand-written
state machine without a planner (scripted.py).
"""

from __future__ import annotations

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
