"""Which Fast DDS profile variable a process sets, by the installed Fast DDS version.

Pure metadata look-ups (no rclpy): the two generations are simulated by replacing
the wheel metadata; the real effect (a crashed peer leaves the graph within the short
lease) is what the killed-server tests of test_service_state.py and
test_simple_action_state.py measure on the installed distribution.
"""

from __future__ import annotations

from importlib import metadata

import pytest

from smach.ros import dds


def installed(monkeypatch: pytest.MonkeyPatch, wheels: dict[str, str], distro: str = "") -> None:
    def version(name: str) -> str:
        if name not in wheels:
            raise metadata.PackageNotFoundError(name)
        return wheels[name]

    monkeypatch.setattr(dds.metadata, "version", version)
    if distro:
        monkeypatch.setenv("ROS_DISTRO", distro)
    else:
        monkeypatch.delenv("ROS_DISTRO", raising=False)


def test_jazzy_fast_dds_2_reads_the_fastrtps_variable(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, {"ros-fastrtps": "2.14.5"})
    assert dds.fast_dds_version() == (2, 14, 5)
    assert dds.profiles_variable() == "FASTRTPS_DEFAULT_PROFILES_FILE"
    assert dds.profile_environment("/tmp/p.xml") == {"FASTRTPS_DEFAULT_PROFILES_FILE": "/tmp/p.xml"}


def test_kilted_fast_dds_3_reads_the_fastdds_variable(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, {"ros-fastdds": "3.2.3"})
    assert dds.fast_dds_version() == (3, 2, 3)
    assert dds.profiles_variable() == "FASTDDS_DEFAULT_PROFILES_FILE"


def test_without_wheels_ros_distro_decides(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, {}, distro="jazzy")
    assert dds.profiles_variable() == "FASTRTPS_DEFAULT_PROFILES_FILE"
    installed(monkeypatch, {}, distro="kilted")
    assert dds.profiles_variable() == "FASTDDS_DEFAULT_PROFILES_FILE"
    installed(monkeypatch, {})
    assert dds.fast_dds_version() is None
    assert dds.profiles_variable() == "FASTDDS_DEFAULT_PROFILES_FILE"


def test_a_profile_counts_as_selected_only_in_the_variable_fast_dds_reads(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    installed(monkeypatch, {"ros-fastrtps": "2.14.5"})
    monkeypatch.delenv("FASTRTPS_DEFAULT_PROFILES_FILE", raising=False)
    monkeypatch.setenv("FASTDDS_DEFAULT_PROFILES_FILE", "/etc/ignored_by_2x.xml")
    assert dds.selected_profile() is None
    monkeypatch.setenv("FASTRTPS_DEFAULT_PROFILES_FILE", "/etc/read_by_2x.xml")
    assert dds.selected_profile() == "/etc/read_by_2x.xml"
