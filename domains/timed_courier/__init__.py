"""timed_courier: a courier with a battery fetches parcels through a fire door.

Temporal and numeric: durative drive / pass-door / hold-door / recharge / grab /
hand-over, a battery (``charge-level``), distances and speeds as numbers, and a
numeric goal (``(>= (delivered) 1)``). The helper must hold the fire door open
*while* the courier passes (two actions that overlap). Planned by Kairos or TAMER
(``--planner auto``) and dispatched as a temporal plan; see README.md.
"""

from .scripted import scripted
from .skills import setup

__all__ = ["scripted", "setup"]
