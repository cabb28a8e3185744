"""robosim_hospital: three robots serve a stream of orders on a hospital floor (see
README.md).

The world, its goals, its order streams and its events are YAML files; the planned
mission's skills are plan_bridge's robosim skills. The Python here is the study's
baseline: :func:`scripted`, the orders dispatched by hand (first come, first served, to
the nearest idle robot) and served by one SMACH machine per robot.
"""

from .scripted import scripted

__all__ = ["scripted"]
