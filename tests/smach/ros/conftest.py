"""Fixtures for the smach.ros tests: a fresh rclpy context per test, server processes.

Every test here talks real ROS 2 over DDS, on this machine only: tests/conftest.py
sets ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and a random ROS_DOMAIN_ID, which the
server subprocesses inherit.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from smach.ros.dds import profile_environment

try:
    from smach.ros import _api
    from smach.ros.executor import SmachExecutor, wait_for_callbacks
except ImportError:  # no ros extra: each test module skips itself (importorskip)
    _api = None

HERE = Path(__file__).parent
SERVERS = HERE / "ros_servers.py"
SHORT_LEASE = HERE / "short_lease.xml"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if HERE in Path(str(item.fspath)).parents:
            item.add_marker(pytest.mark.ros)


class Ros:
    """One test's ROS world: its context, nodes, executors and server processes."""

    def __init__(self) -> None:
        assert _api is not None
        self.context = _api.rclpy.Context()
        _api.rclpy.init(context=self.context)
        self._nodes: list[Any] = []
        self._executors: list[tuple[Any, threading.Thread]] = []
        self._processes: list[subprocess.Popen[str]] = []
        #: Set when the test ends: in-process servers end their running goals.
        self.closing = threading.Event()

    def node(self, name: str, *, spin: bool = False) -> Any:
        """A node in this test's context; ``spin=True`` spins it in a thread."""
        node = _api.rclpy.create_node(name, context=self.context)
        self._nodes.append(node)
        if spin:
            self.spin(node)
        return node

    def spin(self, node: Any, executor: Any = None) -> Any:
        executor = executor or _api.SingleThreadedExecutor(context=self.context)
        executor.add_node(node)
        stop = threading.Event()

        def run() -> None:
            while not stop.is_set() and self.context.ok():
                try:
                    executor.spin_once(timeout_sec=0.05)
                except Exception:
                    if self.context.ok():
                        raise
                    return

        thread = threading.Thread(target=run, daemon=True, name=f"test-spin-{node.get_name()}")
        thread.start()
        thread.stop = stop  # type: ignore[attr-defined]
        self._executors.append((executor, thread))
        return executor

    def server(self, *args: str, ready_timeout: float = 20.0) -> subprocess.Popen[str]:
        """Start ros_servers.py with ``args`` and wait for its ``ready`` line."""
        # Fast DDS 2.x (Jazzy) and 3.x (Kilted) read the profile from differently
        # named variables: the one of the installed version.
        env = dict(os.environ, **profile_environment(SHORT_LEASE))
        process = subprocess.Popen(
            [sys.executable, str(SERVERS), *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        self._processes.append(process)
        assert process.stdout is not None
        deadline = time.monotonic() + ready_timeout
        line = process.stdout.readline()
        if line.strip() != "ready" or time.monotonic() > deadline:
            process.kill()
            raise RuntimeError(f"server {args} did not start: {line!r} {process.stderr.read()}")  # type: ignore[union-attr]
        return process

    def close(self) -> None:
        self.closing.set()
        for process in self._processes:
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self._processes:
            try:
                process.wait(2)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)
            for stream in (process.stdout, process.stderr):
                if stream is not None:
                    stream.close()
        for _, thread in self._executors:
            thread.stop.set()  # type: ignore[attr-defined]
        for executor, thread in self._executors:
            thread.join(5)
            # rclpy's shutdown does not wait for running callbacks: wait here, so that
            # no node is destroyed under one (InvalidHandle in an executor thread).
            wait_for_callbacks(executor, 5)
            executor.shutdown(timeout_sec=0)
        helper = SmachExecutor._instances.get(id(self.context))
        if helper is not None:
            helper.shutdown()
        for node in self._nodes:
            node.destroy_node()
        _api.rclpy.shutdown(context=self.context)


@pytest.fixture
def ros() -> Iterator[Ros]:
    world = Ros()
    try:
        yield world
    finally:
        world.close()
