"""The picture of the viewer's Gantt view in docs/introspection.md.

Runs the timed_courier mission (seed 3, fail rate 0.3: failed actions, a replan and a
retry) with a journal, replays the journal in the viewer, opens the Gantt view in
headless Chromium (Playwright, Debian's /usr/bin/chromium; never `playwright
install`) and saves a screenshot.

    python tools/gantt_screenshot.py                       # docs/images/viewer-gantt.png
    python tools/gantt_screenshot.py OUT.png [--journal RUN.jsonl]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "viewer-gantt.png"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"]


def record(journal: Path) -> None:
    """Run the mission at time scale 0.01 (a plan second is 10 ms of wall time)."""
    from plan_bridge.cli import main

    code = main(
        [
            "run",
            str(ROOT / "domains" / "timed_courier"),
            "--seed",
            "3",
            "--fail-rate",
            "0.3",
            "--time-scale",
            "0.01",
            "--journal",
            str(journal),
            "--quiet",
        ]
    )
    if code:
        raise RuntimeError(f"the mission failed (exit {code})")


def take(
    out: Path, journal: Path, width: int = 1400, height: int = 820, browser: Any = None
) -> int:
    """Screenshot the Gantt view of ``journal`` into ``out``; return its row count.

    ``browser``: a Playwright browser to use (default: launch Chromium here)."""
    from smach.introspection import JournalSource, serve

    with serve(JournalSource(journal), quiet=True) as viewer:
        if browser is not None:
            return _shoot(browser, viewer.url, out, width, height)
        from playwright.sync_api import sync_playwright

        if not Path(CHROMIUM).exists():
            raise RuntimeError(f"no chromium at {CHROMIUM}: apt-get install -y chromium")
        with sync_playwright() as p:
            launched = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                return _shoot(launched, viewer.url, out, width, height)
            finally:
                launched.close()


def _shoot(browser: Any, url: str, out: Path, width: int, height: int) -> int:
    page = browser.new_page(viewport={"width": width, "height": height})
    try:
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        page.wait_for_selector("#gantt-toggle:not([hidden])", timeout=20_000)
        page.click("#gantt-toggle")
        page.wait_for_selector("body[data-gantt-drawn]", timeout=20_000)
        rows = int(page.get_attribute("body", "data-gantt-drawn") or 0)
        out.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(out))
    finally:
        page.close()
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=OUT)
    parser.add_argument("--journal", type=Path, help="replay this journal (default: run one)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        journal = args.journal
        if journal is None:
            journal = Path(tmp) / "timed_courier.jsonl"
            record(journal)
        rows = take(args.out, journal)
    print(f"{args.out}: Gantt view of {rows} actions")
    return 0


if __name__ == "__main__":
    sys.exit(main())
