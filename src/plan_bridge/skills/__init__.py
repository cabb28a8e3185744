"""Stage 3, skills: how one plan action becomes a SMACH sub-state-machine.

* :mod:`~plan_bridge.skills.registry`: :class:`Skill` and :class:`SkillRegistry` (a
  factory per PDDL action, the outcome contract, the userdata keys a skill gets);
* :mod:`~plan_bridge.skills.kit`: building blocks the missions' skills share.

Compiling a whole plan into a machine and running it is :mod:`plan_bridge.execution`.
"""

from __future__ import annotations

from plan_bridge.skills.registry import Skill, SkillRegistry

__all__ = ["Skill", "SkillRegistry"]
