"""robosim_two_robots: two robots deliver parts in a pyrobosim workshop (see README.md).

The world, its goals and its events are YAML files; the planned mission's skills are
plan_bridge's robosim skills. The Python here is the study's baseline: :func:`scripted`,
the mission written by hand as one SMACH machine per robot, both running at once.
"""

from .scripted import scripted

__all__ = ["scripted"]
