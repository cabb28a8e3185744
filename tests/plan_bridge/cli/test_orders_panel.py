"""The viewer's queue panel in headless Chromium (Playwright, Debian's /usr/bin/chromium):
a real `plan-bridge run --orders-open --control`, orders sent and cancelled from the page,
and the same rows replayed from the run's journal (`plan-bridge view RUN.jsonl`)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from smach.introspection import JournalSource, serve
from smach.introspection.journal import read_journal

ROOMS = Path(__file__).parents[1] / "data" / "rooms"
ARTIFACTS = Path(__file__).parents[3] / "artifacts" / "viewer"

pytestmark = [pytest.mark.browser, pytest.mark.timeout(180)]


class Run:
    """`plan-bridge run ROOMS p02 --orders-open --control --start-paused` in a subprocess."""

    def __init__(self, journal: Path) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [sys.executable, "-m", "plan_bridge", "run", str(ROOMS), "--problem", "p02.pddl",
             "--orders-open", "--control", "--start-paused", "--journal", str(journal)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )  # fmt: skip
        self.lines: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_line(self, pattern: str, timeout: float = 60.0) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                found = re.match(pattern, line)
                if found:
                    return found
            if self.process.poll() is not None and not self.reader.is_alive():
                break
            time.sleep(0.05)
        raise AssertionError(f"no line like {pattern!r} in:\n" + "\n".join(self.lines))

    def close(self) -> int:
        """Ctrl-C (the viewer serves a finished mission until then); kill after 30 s."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)
        self.reader.join(10)
        assert self.process.stderr is not None
        self.process.stderr.close()
        return self.process.returncode


def row(status: str, order: str) -> str:
    """The selector of ``order``'s row once it has ``status``."""
    return f"#orders tr[data-order='{order}'][data-status='{status}']"


def send(page: Any, goal: str, priority: int = 0) -> None:
    page.fill("#order-goal", goal)
    page.fill("#order-priority", str(priority))
    page.click("#order-send")
    page.wait_for_selector(f"#order-message:has-text('sent: {goal}')", timeout=20_000)


def test_orders_sent_and_cancelled_from_the_page_and_replayed_from_the_journal(
    browser: Any, tmp_path: Path
) -> None:
    journal = tmp_path / "run.jsonl"
    run = Run(journal)
    try:
        url = run.wait_line(r"control: (http://\S+)").group(1)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        # A mission open for orders: the panel and its form, before any order came.
        page.wait_for_selector("#order-form", state="visible", timeout=20_000)
        assert page.is_visible("#orders-empty")
        # Started paused: the plan for the first order is made and held.
        send(page, "(at r2 office)")
        page.wait_for_selector(row("assigned", "o1"), timeout=30_000)
        assert page.inner_text(f"{row('assigned', 'o1')} .orob") == "r2"
        page.click("#orders button[data-cancel='o1']")
        page.wait_for_selector(row("cancelled", "o1"), timeout=30_000)
        assert "cancelled (viewer)" in page.inner_text("#orders tr[data-detail='o1']")
        assert page.locator("#orders button[data-cancel='o1']").count() == 0
        send(page, "(item-at cup office)", priority=2)
        send(page, "(at r9 office)")
        page.click("#ctl-resume")
        page.wait_for_selector(row("done", "o2"), timeout=30_000)
        page.wait_for_selector(row("refused", "o3"), timeout=30_000)
        assert page.inner_text(f"{row('done', 'o2')} .orob") == "r1"
        assert re.fullmatch(r"\d+\.\d s", page.inner_text(f"{row('done', 'o2')} .olat"))
        assert page.inner_text(f"{row('done', 'o2')} .oprio") == "p2"
        assert "unknown object 'r9'" in page.inner_text("#orders tr[data-detail='o3'] .oreason")
        assert page.inner_text("#orders-count") == "3 · 0 open"
        # The timeline lists the changes too.
        assert page.locator("#events tr[data-kind='order']").count() >= 5
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.locator("#orders").screenshot(path=str(ARTIFACTS / "orders-panel-live.png"))
        page.click("#ctl-preempt")  # open for orders: the mission goes on until stopped
        run.wait_line(r"viewer: .* the mission ended")
        assert errors == []
        page.close()
    finally:
        run.close()
    # The journal replayed (`plan-bridge view RUN.jsonl`): the same rows, read-only,
    # and the slider shows the orders as they were.
    _, records = read_journal(journal)
    cancelled = next(
        n + 1
        for n, r in enumerate(records)
        if r.get("kind") == "order" and (r["order"], r["status"]) == ("o1", "cancelled")
    )
    with serve(JournalSource(journal), quiet=True) as viewer:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        page.wait_for_selector(row("done", "o2"), timeout=20_000)
        assert page.is_hidden("#order-form")
        assert page.locator("#orders button[data-cancel]").count() == 0
        page.fill("#slider", str(cancelled))
        page.wait_for_selector(f"body[data-index='{cancelled}']", timeout=10_000)
        page.wait_for_selector(row("cancelled", "o1"), timeout=10_000)
        assert page.locator("#orders tr.ohead").count() == 1  # o2 and o3 came later
        page.close()
