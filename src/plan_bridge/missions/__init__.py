"""Stage 5, missions: a domain folder (``domains/NAME``) loaded as a runnable target.

* :mod:`~plan_bridge.missions.target`: :class:`Target`, :class:`MissionSetup`,
  :class:`ScriptedMission` (PDDL + skills + simulated world + scripted baseline);
* :mod:`~plan_bridge.missions.mission`: :func:`load_target` (a domain folder, a bare
  domain.pddl or a pyrobosim world; :mod:`~plan_bridge.missions.world_target`);
* :mod:`~plan_bridge.missions.problem_writer`: writing problem files for a
  mission's generator.

The command line over missions is :mod:`plan_bridge.cli`, the study
:mod:`plan_bridge.study`.
"""
