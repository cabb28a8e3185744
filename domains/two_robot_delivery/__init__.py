"""Two-robot delivery: two robots fetch items from two storerooms at the same time.

``plan-bridge run domains/two_robot_delivery`` plans for both robots with one PDDL
planner call and runs the independent steps of the two robots concurrently, each as
a hand-written SMACH skill (skills.py) in a thread-safe simulated world with seeded
per-robot faults (world.py); ``scripted`` is the same mission as one hand-written
state machine without a planner (scripted.py).
"""

from __future__ import annotations

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
