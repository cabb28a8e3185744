"""Stage 1, reading and checking PDDL: text with positions, structural checks, the task.

* :mod:`~plan_bridge.pddl.source`: decoding, positions (``file:line:column``) and the
  cheap structural checks that run before unified-planning is imported;
* :mod:`~plan_bridge.pddl.task`: :class:`PlanningTask` (the UP problem with its
  facts, actions and source text), :func:`load_task`, facts;
* :mod:`~plan_bridge.pddl.reachability`: relaxed reachability (why a goal is unreachable);
* :mod:`~plan_bridge.pddl.up_runtime`: importing unified-planning lazily and lean
  problem copies.

Nothing here plans or executes; everything else in plan_bridge builds on it.
"""
