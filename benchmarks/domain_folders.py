"""The mission folders of ``domains/`` that run as simulated missions (for benchmarks
that sweep them all)."""

from __future__ import annotations

from pathlib import Path


def mission_folders(domains: Path) -> list[str]:
    """Every mission in ``domains`` (each folder with a domain.pddl), by name; not the
    folders whose skills.toml binds actions to ROS 2 (they need their robot running)."""
    from plan_bridge.skills.ros.entries import runs_on_ros

    return sorted(
        d.name for d in domains.iterdir() if (d / "domain.pddl").is_file() and not runs_on_ros(d)
    )
