"""Stage 5, missions: a domain folder (``domains/NAME``) loaded as a runnable target.

* :mod:`~plan_bridge.missions.mission`: :class:`Target`, :class:`MissionSetup`,
  :func:`load_target` (PDDL + skills + simulated world + scripted baseline);
* :mod:`~plan_bridge.missions.problem_writer`: writing problem files for a
  mission's generator.

The command line over missions is :mod:`plan_bridge.cli`, the study
:mod:`plan_bridge.study`.
"""
