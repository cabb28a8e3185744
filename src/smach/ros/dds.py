"""Which Fast DDS is installed, and how to give its participants an XML profile.

No rclpy needed: the version comes from the installed wheels' metadata. A process
selects a default profile for the DDS participants it creates through an environment
variable, read when the first participant is made (``rclpy.init``). The variable's
name is the knob that differs between the two Fast DDS generations ROS 2 ships:

* Fast DDS 2.x (ROS 2 Jazzy: ``ros-jazzy-rclpy[fastrtps]`` installs Fast DDS 2.14,
  package ``ros-fastrtps``) reads ``FASTRTPS_DEFAULT_PROFILES_FILE`` only;
* Fast DDS 3.x (ROS 2 Kilted: ``ros-rclpy[fastrtps]`` 9.x installs Fast DDS 3.2,
  package ``ros-fastdds``) renamed it ``FASTDDS_DEFAULT_PROFILES_FILE`` and ignores
  the old name.

The profile's XML (a participant's ``leaseDuration`` and ``leaseAnnouncement``) is the
same for both. Setting the wrong variable is silently ignored: a crashed peer then
stays in the ROS graph for Fast DDS's default 20 s lease.
"""

from __future__ import annotations

import os
from importlib import metadata

__all__ = [
    "FAST_DDS_2_VARIABLE",
    "FAST_DDS_3_VARIABLE",
    "fast_dds_version",
    "profile_environment",
    "profiles_variable",
    "selected_profile",
]

#: The default-profile variable of Fast DDS 2.x (ROS 2 Jazzy and older).
FAST_DDS_2_VARIABLE = "FASTRTPS_DEFAULT_PROFILES_FILE"
#: The default-profile variable of Fast DDS 3.x (ROS 2 Kilted and newer).
FAST_DDS_3_VARIABLE = "FASTDDS_DEFAULT_PROFILES_FILE"

#: Wheel distribution names of Fast DDS, newest generation first.
_DISTRIBUTIONS = ("ros-fastdds", "ros-fastrtps")
#: ROS 2 distributions that ship Fast DDS 2.x (for a ROS installed without wheels).
_FAST_DDS_2_DISTROS = frozenset({"foxy", "galactic", "humble", "iron", "jazzy"})


def _parse(text: str) -> tuple[int, ...]:
    parts: list[int] = []
    for piece in text.split("."):
        digits = "".join(c for c in piece if c.isdigit())
        if not digits:
            break
        parts.append(int(digits))
    return tuple(parts)


def fast_dds_version() -> tuple[int, ...] | None:
    """The installed Fast DDS version, e.g. ``(2, 14, 5)``; None if no wheel says.

    Without the wheels (ROS installed from Debian packages), ``ROS_DISTRO`` decides:
    ``(2,)`` for Jazzy and older, ``(3,)`` for newer distributions.
    """
    for name in _DISTRIBUTIONS:
        try:
            return _parse(metadata.version(name))
        except metadata.PackageNotFoundError:
            continue
    distro = os.environ.get("ROS_DISTRO", "").strip().lower()
    if not distro:
        return None
    return (2,) if distro in _FAST_DDS_2_DISTROS else (3,)


def profiles_variable() -> str:
    """The environment variable the installed Fast DDS reads its default profile from
    (Fast DDS 3.x's name when the version is unknown)."""
    version = fast_dds_version()
    if version is not None and version[:1] < (3,):
        return FAST_DDS_2_VARIABLE
    return FAST_DDS_3_VARIABLE


def selected_profile() -> str | None:
    """The default profile this process's participants will load, if one is selected."""
    return os.environ.get(profiles_variable()) or None


def profile_environment(profile: str | os.PathLike[str]) -> dict[str, str]:
    """The variable that selects ``profile`` for the installed Fast DDS, as a mapping
    to merge into a child process's environment (``dict(os.environ, **...)``)."""
    return {profiles_variable(): os.fspath(profile)}
