"""A short DDS lease for robot processes, so that executives notice a dead robot fast.

When a process dies without leaving the ROS graph (SIGKILL, a crash, power loss),
its peers keep it as alive until its participant's lease runs out: 20 s with Fast
DDS's default. A robot node (:mod:`plan_bridge.ros.skill_server`) selects a profile
with a lease of about two seconds instead, and the executive's
:mod:`~plan_bridge.ros.connection` sees the robot gone within that time.

The profile is selected through the variable the installed Fast DDS reads
(:func:`smach.ros.dds.profiles_variable`): ``FASTRTPS_DEFAULT_PROFILES_FILE`` for
Fast DDS 2.x (ROS 2 Jazzy), ``FASTDDS_DEFAULT_PROFILES_FILE`` for 3.x (Kilted).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from smach.ros.dds import profiles_variable, selected_profile

__all__ = ["SHORT_LEASE_PROFILE", "select_short_lease"]

#: Fast DDS participant profile with a short lease: when the robot process dies
#: (SIGKILL, crash, power loss), it leaves the ROS graph after ``{lease}`` seconds
#: instead of Fast DDS's default 20 s, so executives notice within that time. The
#: same XML works for Fast DDS 2.x and 3.x.
SHORT_LEASE_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com"><profiles>
  <participant profile_name="plan_bridge_robot_lease" is_default_profile="true"><rtps><builtin>
    <discovery_config>
      <leaseDuration><sec>{sec}</sec><nanosec>{nanosec}</nanosec></leaseDuration>
      <leaseAnnouncement><sec>{asec}</sec><nanosec>{ananosec}</nanosec></leaseAnnouncement>
    </discovery_config>
  </builtin></rtps></participant>
</profiles></dds>
"""


def select_short_lease(lease: float) -> Path | None:
    """Write a Fast DDS profile with a ``lease`` seconds lease and select it for the
    participants this process creates from now on (call before ``rclpy.init``).

    Returns the profile's file (the caller removes it at exit), or None when ``lease``
    is 0 or a profile is already selected (the installed Fast DDS's variable is set).
    """
    if lease <= 0 or selected_profile():
        return None
    announce = max(0.1, lease / 4)
    text = SHORT_LEASE_PROFILE.format(
        sec=int(lease),
        nanosec=round((lease % 1) * 1e9),
        asec=int(announce),
        ananosec=round((announce % 1) * 1e9),
    )
    handle, name = tempfile.mkstemp(prefix="plan_bridge_lease_", suffix=".xml")
    with os.fdopen(handle, "w") as file:
        file.write(text)
    os.environ[profiles_variable()] = name
    return Path(name)
