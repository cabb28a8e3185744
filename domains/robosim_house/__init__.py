"""robosim_house: doors, a table to clear and rooms to inspect, in a pyrobosim world
(see README.md).

The world, its goals and its events are YAML files; the planned mission's skills are
plan_bridge's robosim skills. The Python here is the study's baseline: :func:`scripted`,
the mission written by hand as one SMACH machine over the same skills.
"""

from .scripted import scripted

__all__ = ["scripted"]
