"""The short DDS lease a robot process selects, through the variable the installed
Fast DDS reads (FASTRTPS_DEFAULT_PROFILES_FILE for 2.x, FASTDDS_... for 3.x)."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import pytest

# plan_bridge.ros (the package) imports its ROS clients, hence rclpy.
pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from plan_bridge.ros.lease import select_short_lease
from smach.ros.dds import profiles_variable

pytestmark = pytest.mark.ros

VARIABLE = profiles_variable()
NS = {"dds": "http://www.eprosima.com"}


def _unset(monkeypatch: pytest.MonkeyPatch) -> None:
    """Unset the variable so that the test's end restores it as it was, whatever the
    code under test sets (a ``delenv`` of an unset variable records nothing to undo,
    and a path to a removed profile would then break the DDS of every later test)."""
    monkeypatch.setenv(VARIABLE, "")
    monkeypatch.delenv(VARIABLE)


def test_a_lease_writes_a_profile_with_that_lease_and_selects_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _unset(monkeypatch)
    profile = select_short_lease(2.5)
    assert profile is not None
    try:
        assert os.environ[VARIABLE] == str(profile)
        config = ET.parse(profile).getroot().find(".//dds:discovery_config", NS)
        assert config is not None
        lease = config.find("dds:leaseDuration", NS)
        announce = config.find("dds:leaseAnnouncement", NS)
        assert lease is not None and announce is not None
        assert [lease.findtext(f"dds:{k}", namespaces=NS) for k in ("sec", "nanosec")] == [
            "2",
            "500000000",
        ]
        # Announced four times per lease, so one lost announcement is not a death.
        assert [announce.findtext(f"dds:{k}", namespaces=NS) for k in ("sec", "nanosec")] == [
            "0",
            "625000000",
        ]
    finally:
        profile.unlink()


def test_no_lease_or_a_profile_already_chosen_is_left_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _unset(monkeypatch)
    assert select_short_lease(0) is None
    monkeypatch.setenv(VARIABLE, "/etc/their_profile.xml")
    assert select_short_lease(2.0) is None
    assert os.environ[VARIABLE] == "/etc/their_profile.xml"
