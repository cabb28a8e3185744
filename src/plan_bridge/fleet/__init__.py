"""Fleets: a goal shared out to robots by route cost, each robot planned on its own.

* :mod:`.jobs`: the goal's atoms grouped into jobs, and jobs allocated to robots;
* :mod:`.planner`: :class:`~.planner.FleetPlanner`, the planner of a fleet's tasks.
"""
