"""plan_bridge.ros: planned missions across processes over ROS 2.

:class:`SkillServer` (``python -m plan_bridge.ros.skill_server``) serves every
action of a PDDL domain as a ROS 2 action backed by a simulated world;
:func:`ros_skills` builds a skill registry of ROS clients of it, so an
:class:`~plan_bridge.execution.executive.Executive` runs its plan on the remote robot. The
wire format is in :mod:`plan_bridge.ros.protocol`. For a domain folder the
server runs the domain's own skill machines against its simulated world (for a
pyrobosim world, the robosim skills against its ``RobosimWorld``), and
:class:`plan_bridge.ros.connection.RobotConnection` starts or finds such a robot
node for ``plan-bridge run --ros``.
"""

from __future__ import annotations

from typing import Any

from plan_bridge.ros.protocol import decode_result, encode_result
from plan_bridge.ros.skills import remote_facts, remote_info, ros_skill, ros_skills

__all__ = [
    "SkillServer",
    "decode_result",
    "encode_result",
    "remote_facts",
    "remote_info",
    "ros_skill",
    "ros_skills",
]


def __getattr__(name: str) -> Any:
    # Imported on demand so that ``python -m plan_bridge.ros.skill_server`` does not
    # find its own module already imported by the package.
    if name == "SkillServer":
        from plan_bridge.ros.skill_server import SkillServer

        return SkillServer
    raise AttributeError(f"module 'plan_bridge.ros' has no attribute {name!r}")
