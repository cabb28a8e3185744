"""Shared pyrobosim worlds for the robosim tests (skipped, with the reason, without pyrobosim)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def test_world_file() -> Path:
    from pyrobosim.utils.general import get_data_folder

    return Path(get_data_folder()) / "test_world.yaml"


@pytest.fixture(scope="session")
def test_world_model(test_world_file: Path):  # type: ignore[no-untyped-def]
    from plan_bridge.robosim.description import describe_world
    from plan_bridge.robosim.loading import load_world_file

    return describe_world(load_world_file(test_world_file))
