"""Test-wide settings: keep ROS 2 traffic on this machine, one DDS domain per run (and
per xdist worker), Ctrl-C reaches the command-line programs the tests start; every
test is put in its tier (tests/tiers.py) and ``--store-durations`` records how long
each took in tests/durations.json."""

from __future__ import annotations

import os
import shutil
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import tiers

# DDS would otherwise multicast off the machine; a random domain per run keeps
# concurrent test runs apart, and one more per xdist worker keeps the workers apart.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_DOMAIN_ID"] = tiers.worker_ros_domain(os.environ, tiers.xdist_worker())

# A suite started in the background by a non-interactive shell (`.ci/run &`) inherits
# SIGINT ignored, and every program it starts would too: the tests that press Ctrl-C
# on `plan-bridge run --viewer` or the viewer CLI would wait for an exit that never
# comes. A handled signal is reset to its default in the programs started from here.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("tiers", "test tiers (tests/tiers.py)")
    group.addoption(
        "--store-durations",
        action="store_true",
        help="after the run, write each test's seconds to the durations file "
        "(merged with the tests this run did not run)",
    )
    group.addoption(
        "--durations-path",
        default=str(tiers.DURATIONS_FILE),
        help="the durations file read to find slow tests and written by "
        "--store-durations (default: tests/durations.json)",
    )


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("store_durations") and not hasattr(config, "workerinput"):
        recorder = tiers.DurationRecorder(Path(config.getoption("durations_path")))
        config.pluginmanager.register(recorder, "tiers-durations")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    # tryfirst: before -m deselects by these markers and xdist reads the groups.
    collected = [tiers.plain_nodeid(item.nodeid) for item in items]
    recorder = config.pluginmanager.get_plugin("tiers-durations")
    if isinstance(recorder, tiers.DurationRecorder):
        recorder.collected.update(collected)
    workeroutput = getattr(config, "workeroutput", None)
    if workeroutput is not None:  # an xdist worker: tell the controller what it collected
        workeroutput["tiers_collected"] = collected
    workerinput = getattr(config, "workerinput", {})
    if "tiers_durations" in workerinput:  # read once by the controller: the same for all
        durations = workerinput["tiers_durations"]
    else:
        durations = tiers.load_durations(Path(config.getoption("durations_path")))
    tiers.assign(items, durations, groups=config.pluginmanager.hasplugin("xdist"))


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    # xdist's controller, starting a worker: every worker groups and tiers the tests
    # from the same durations, even if the file changes while they start.
    path = Path(node.config.getoption("durations_path"))
    node.workerinput["tiers_durations"] = tiers.load_durations(path)


@pytest.fixture(scope="session", autouse=True)
def _planner_workers_stop_with_the_tests() -> Iterator[None]:
    """The planner's worker processes this process started stop when its tests end,
    not at its exit: under coverage each saves its data as it exits, and that must come
    before pytest-cov combines the data files (else they stay behind, uncounted)."""
    yield
    worker = sys.modules.get("plan_bridge.planning.worker")
    if worker is not None:
        worker._close_default_pool()


#: The viewer's browser tests: Debian's chromium, headless (as root: no sandbox).
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"]


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """A headless chromium driven by Playwright, one for a test module (skips the test
    when Playwright or chromium is not installed)."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    if not Path(CHROMIUM).exists():
        pytest.skip("chromium is not installed")
    with sync_api.sync_playwright() as p:
        launched = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield launched
        launched.close()
