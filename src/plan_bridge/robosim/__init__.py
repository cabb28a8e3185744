"""pyrobosim worlds as targets of plan_bridge (the ``sim`` extra: ``pip install .[sim]``).

A pyrobosim world file is a mission: :mod:`.problem` writes the planning problem of the
shipped temporal and numeric domain (``domain.pddl``) from the world and a goal in
pyrobosim's vocabulary; :class:`.world.RobosimWorld` is the
:class:`~plan_bridge.execution.world.World` the executive acts on (simulated time,
pyrobosim's own seeded faults, sensing, events); :mod:`.skills` are SMACH skills over
the robot's API; :mod:`.events` changes the world by itself at simulated times.

pyrobosim is imported only by the modules of this package that need it, when they run:
``import plan_bridge`` works without it. See docs/sim.md.
"""
