"""robosim_search: find an object people moved, and fetch it (see README.md).

The world, its goals and its events are YAML files; the planned mission's skills are
plan_bridge's robosim skills (with ``search``). The Python here is the study's baseline:
:func:`scripted`, a hand-written search and fetch over the same skills.
"""

from .scripted import scripted

__all__ = ["scripted"]
