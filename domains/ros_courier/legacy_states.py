"""A SMACH state kept from an older program: the skill map's [drop] entry names this
factory, which returns a smach_ros ServiceState written the ROS 1 way (no node)."""

from __future__ import annotations

from typing import Any

import smach
import smach_ros


def open_gripper(robot: str, parcel: str, place: str) -> smach.State:
    """Open the gripper of ``robot`` (``std_srvs/srv/SetBool`` with ``data = false``)."""
    from std_srvs.srv import SetBool

    def released(ud: smach.UserData, response: Any) -> str:
        return "succeeded" if response.success else "aborted"

    return smach_ros.ServiceState(
        "/courier/gripper",
        SetBool,
        request=SetBool.Request(data=False),
        response_cb=released,
        server_wait_timeout=5.0,
        call_timeout=5.0,
    )
