"""Stage 4, execution: plans compiled into SMACH and run against a world.

* :mod:`~plan_bridge.execution.semantics`: grounded actions, preconditions and
  effects, plan validation from a state;
* :mod:`~plan_bridge.execution.world`: the World protocol (what the executive needs of
  the world it acts on);
* :mod:`~plan_bridge.execution.steps`: a plan's steps as SMACH states;
* :mod:`~plan_bridge.execution.compile`: a plan -> a SMACH machine of skills;
* :mod:`~plan_bridge.execution.temporal`: a temporal plan -> a dispatcher of timed
  steps (with :mod:`~plan_bridge.execution.temporal_network`,
  :mod:`~plan_bridge.execution.timed_step` and :mod:`~plan_bridge.execution.timeline`);
* :mod:`~plan_bridge.execution.executive`: the :class:`Executive` loop (dispatch,
  validate, repair, replan), itself a SMACH state;
* :mod:`~plan_bridge.execution.repair`: the recovery ladder, a list of strategies;
* :mod:`~plan_bridge.execution.simulation`: simulated worlds with faults;
* :mod:`~plan_bridge.execution.events`: the executive's events.
"""
