"""`plan-bridge run --viewer`: a watchable mission, and a page that stays until Ctrl-C.

The browser part runs in headless Chromium (Playwright, Debian's chromium) and is
skipped when either is missing.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

DOMAINS = Path(__file__).parents[3] / "domains"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"]


class Mission:
    """A `plan-bridge run --viewer` subprocess whose stderr lines are collected."""

    def __init__(self, *args: str) -> None:
        env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [sys.executable, "-m", "plan_bridge", "run", *args],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        self.lines: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_line(self, start: str, timeout: float = 60.0) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = next((line for line in self.lines if line.startswith(start)), None)
            if found is not None:
                return found
            if self.process.poll() is not None and not self.reader.is_alive():
                break
            time.sleep(0.05)
        raise AssertionError(f"no line starting with {start!r} in:\n" + "\n".join(self.lines))

    def url(self) -> str:
        return self.wait_line("smach viewer: ").split(": ", 1)[1].strip()

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
        code = self.process.wait(timeout=30)
        self.close()
        return code

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=10)
        self.reader.join(timeout=10)
        assert self.process.stderr is not None
        self.process.stderr.close()


@pytest.fixture
def mission() -> Iterator[Any]:
    started: list[Mission] = []

    def start(*args: str) -> Mission:
        m = Mission(*args)
        started.append(m)
        return m

    yield start
    for m in started:
        m.close()


def view(url: str) -> dict[str, Any]:
    with urllib.request.urlopen(url + "api/view", timeout=10) as response:
        data: dict[str, Any] = json.load(response)
        return data


@pytest.mark.timeout(180)
def test_the_viewer_keeps_serving_the_finished_mission_until_ctrl_c(mission: Any) -> None:
    run = mission(str(DOMAINS / "fetch_drink"), "--viewer", "--time-scale", "0", "--quiet")
    url = run.url()
    run.wait_line("viewer: ")  # the mission ended, and the process says so
    assert "still serving it, Ctrl-C to stop" in run.wait_line("viewer: ")
    assert run.process.poll() is None
    deadline = time.monotonic() + 30  # the viewer's pump folds the last events
    while view(url)["running"] and time.monotonic() < deadline:
        time.sleep(0.1)
    finished = view(url)
    assert finished["running"] is False and finished["root_outcome"] == "succeeded"
    assert run.stop() == 0


#: Page script: every path drawn active in #graph from now on, in ``window.seenActive``.
SEEN_ACTIVE = """() => {
  window.seenActive = new Set();
  const graph = document.getElementById("graph");
  const note = () => {
    for (const e of graph.querySelectorAll(".active")) window.seenActive.add(e.dataset.path);
  };
  note();
  new MutationObserver(note).observe(
    graph, { subtree: true, childList: true, attributes: true, attributeFilter: ["class"] }
  );
}"""


@pytest.mark.timeout(180)
@pytest.mark.browser
def test_a_simulated_mission_runs_at_a_pace_the_page_can_show(mission: Any) -> None:
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    if not Path(CHROMIUM).exists():
        pytest.skip("chromium is not installed")
    from plan_bridge.cli import main

    # Held at its first state until the page is up (a loaded machine may take seconds
    # to start the browser), then resumed from the command line.
    run = mission(
        str(DOMAINS / "fetch_drink"), "--viewer", "--time-scale", "0.03",
        "--control", "--start-paused",
    )  # fmt: skip
    url = run.url()
    control = run.wait_line("control: ").split(": ", 1)[1].strip()
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.goto(url)
            page.wait_for_selector("body[data-ready='1']", timeout=20_000)
            # The page notes every state it draws active (polling it from here, on a busy
            # machine, could miss most of them).
            page.evaluate(SEEN_ACTIVE)
            assert main(["control", control, "resume"]) == 0
            # While the mission runs, the page shows its skills' states one after another.
            while not any(line.startswith("viewer: ") for line in run.lines):
                time.sleep(0.1)
                assert run.process.poll() is None, "\n".join(run.lines)
            seen = set(page.evaluate("() => [...window.seenActive]"))
            page.reload()
            page.wait_for_selector("body[data-ready='1']", timeout=20_000)
            assert page.title()  # the page is still served after the mission
        finally:
            browser.close()
    steps = {path.split("/")[3] for path in seen if path.count("/") >= 3}
    assert len(steps) >= 3, seen  # several steps were on screen while they ran
    assert run.stop() == 0
