"""Fixtures shared by the smach core tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from smach_helpers import LogRecorder

import smach
from smach import container as container_module


@pytest.fixture(autouse=True)
def _restore_smach_globals() -> Iterator[None]:
    """Put loggers and the shutdown check back; fail if a test leaves a container open."""
    saved = {
        name: getattr(smach, name)
        for name in ("loginfo", "logwarn", "logdebug", "logerr", "is_shutdown")
    }
    yield
    for name, value in saved.items():
        setattr(smach, name, value)
    stack = container_module._construction.stack
    leftover = list(stack)
    stack.clear()
    assert leftover == [], f"test left containers open: {leftover}"


@pytest.fixture
def logs() -> LogRecorder:
    recorder = LogRecorder()
    recorder.install()
    return recorder
