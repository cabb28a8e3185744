"""The Gantt view of a temporal mission's journal, in headless Chromium (Playwright,
Debian's chromium; skipped when either is missing). A screenshot goes to
artifacts/viewer/ (gitignored)."""

from __future__ import annotations

import importlib.util
import itertools
import json
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.cli import main
from smach.introspection import JournalSource, serve
from smach.introspection.journal import read_journal
from smach.introspection.model import fold

pytestmark = pytest.mark.browser

REPO = Path(__file__).parents[3]
DOMAINS = REPO / "domains"
ARTIFACTS = REPO / "artifacts" / "viewer"
TOOL = REPO / "tools" / "gantt_screenshot.py"


@pytest.fixture(scope="module")
def journal(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """timed_courier, seed 3, fail rate 0.3: failed actions, a replan (several dispatches)."""
    path = tmp_path_factory.mktemp("gantt") / "run.jsonl"
    main(
        [
            "run",
            str(DOMAINS / "timed_courier"),
            "--problem",
            "p01",
            "--seed",
            "3",
            "--fail-rate",
            "0.3",
            "--time-scale",
            "0.005",
            "--journal",
            str(path),
            "--quiet",
        ]
    )
    return path


def _rows(page: Any) -> list[dict[str, Any]]:
    script = """els => els.map(g => {
        const p = g.querySelector('rect.gantt-planned'), a = g.querySelector('rect.gantt-actual');
        return {index: Number(g.dataset.index), outcome: g.dataset.outcome,
                planned: p ? Number(p.getAttribute('width')) : 0,
                actual: a ? Number(a.getAttribute('width')) : 0,
                label: g.querySelector('text.gantt-label').textContent};
    })"""
    rows: list[dict[str, Any]] = page.eval_on_selector_all("#gantt-chart g.gantt-row", script)
    return rows


def test_the_journal_of_a_temporal_mission_folds_into_one_gantt_row_per_started_action(
    journal: Path,
) -> None:
    header, records = read_journal(journal)
    started = [r for r in records if r["kind"] == "action_started"]
    ended = {r["path"] + str(r["time"]): r for r in records if r["kind"] == "action_ended"}
    view = fold(header, records).gantt_json()
    assert view["axis"] == "plan" and view["time_scale"] == 0.005
    # A new dispatch for the replan's plan and the retry's: every one has its rows.
    assert view["dispatches"] >= 2
    assert {r["dispatch"] for r in view["rows"]} == set(range(view["dispatches"]))
    assert [r["index"] for r in view["rows"]] == [r["index"] for r in started]
    assert len(ended) == len(started) and not any(r["running"] for r in view["rows"])
    for row, record in zip(view["rows"], started, strict=True):
        assert row["planned_start"] == record["planned_start"]
        assert row["p1"] - row["p0"] == pytest.approx(record["planned_duration"])
        assert row["a1"] >= row["a0"] >= 0


@pytest.mark.timeout(120)
def test_the_replay_page_draws_planned_and_actual_bars_of_every_action_up_to_the_slider(
    browser: Any, journal: Path
) -> None:
    _, records = read_journal(journal)
    started = [r for r in records if r["kind"] == "action_started"]
    outcomes = [r["outcome"] for r in records if r["kind"] == "action_ended"]
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    with serve(JournalSource(journal), quiet=True) as viewer:
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=10_000)
        page.wait_for_selector(f"#gantt-toggle:text-is('Gantt ({len(started)})')")
        page.click("#gantt-toggle")
        page.wait_for_selector(f"body[data-gantt-drawn='{len(started)}']")
        rows = _rows(page)
        assert sorted(r["index"] for r in rows) == sorted(r["index"] for r in started)
        assert all(r["planned"] > 0 and r["actual"] > 0 for r in rows)
        assert sorted(r["outcome"] for r in rows) == sorted(outcomes)
        assert "aborted" in outcomes  # the seed's faults show as red bars
        assert "(hand-over courier box1 depot)" in " ".join(r["label"] for r in rows)
        assert "plan seconds" in page.inner_text("#gantt-note")
        assert page.is_visible("#gantt-axis text.gantt-unit")
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "gantt-replay.png"))
        # The slider right after the fifth start: five bars, the unfinished ones running.
        fifth = [n for n, r in enumerate(records) if r["kind"] == "action_started"][4] + 1
        ended_by_then = {r["path"] for r in records[:fifth] if r["kind"] == "action_ended"}
        page.fill("#slider", str(fifth))
        page.wait_for_selector(f"body[data-index='{fifth}']")
        page.wait_for_selector("body[data-gantt-drawn='5']")
        rows = _rows(page)
        running = [r for r in rows if r["outcome"] == "running"]
        expected_running = [r for r in started[:5] if r["path"] not in ended_by_then]
        assert len(running) == len(expected_running) >= 1
        assert page.locator("#gantt-chart line.gantt-now").count() == 1  # the moment shown
        # Back to the start: no temporal step yet, the Gantt closes and its button hides.
        page.fill("#slider", "0")
        page.wait_for_selector("body[data-gantt-rows='0']")
        assert page.is_hidden("#gantt-toggle") and page.is_hidden("#gantt-pane")
    page.close()
    assert errors == []


def test_the_view_counts_the_gantt_rows_and_api_gantt_sends_them_at_any_moment(
    journal: Path,
) -> None:
    _, records = read_journal(journal)
    started = [n for n, r in enumerate(records) if r["kind"] == "action_started"]

    def get(url: str) -> Any:
        with urllib.request.urlopen(url) as response:
            return json.loads(response.read())

    with serve(JournalSource(journal), quiet=True) as viewer:
        base = viewer.url.rstrip("/")
        view = get(base + "/api/view")
        assert view["gantt"] == {"rows": len(started), "running": 0}
        assert "rows" in get(base + "/api/gantt") and get(base + "/api/gantt")["axis"] == "plan"
        assert len(get(base + "/api/gantt")["rows"]) == len(started)
        at = started[2] + 1  # right after the third start
        assert len(get(f"{base}/api/gantt?at={at}")["rows"]) == 3
        assert get(base + "/api/gantt?at=0") is None
        assert get(base + "/api/view?at=0")["gantt"] is None


@pytest.mark.timeout(180)
def test_the_live_page_grows_the_running_bars_while_a_temporal_mission_runs(
    browser: Any, tmp_path: Path
) -> None:
    journal = tmp_path / "live.jsonl"
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "plan_bridge", "run", str(DOMAINS / "timed_courier"),
         "--seed", "3", "--fail-rate", "0.3", "--time-scale", "0.05", "--viewer",
         "--journal", str(journal)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    lines: list[str] = []
    reader = threading.Thread(
        target=lambda: lines.extend(line.rstrip("\n") for line in process.stderr or ()),
        daemon=True,
    )
    reader.start()
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        deadline = time.monotonic() + 60
        while not any(line.startswith("smach viewer: ") for line in lines):
            assert time.monotonic() < deadline and process.poll() is None, "\n".join(lines)
            time.sleep(0.05)
        url = next(line for line in lines if line.startswith("smach viewer: ")).split(": ", 1)[1]
        page.goto(url.strip())
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        page.wait_for_selector("#gantt-toggle:not([hidden])", timeout=60_000)
        page.click("#gantt-toggle")
        # While the mission runs: bars of running actions, drawn again as they grow.
        running_widths: dict[int, list[float]] = {}
        while not any(line.startswith("viewer: ") for line in lines):
            for row in _rows(page):
                if row["outcome"] == "running":
                    running_widths.setdefault(row["index"], []).append(row["actual"])
            assert process.poll() is None, "\n".join(lines)
            time.sleep(0.05)
        assert any(len(set(w)) > 1 for w in running_widths.values()), running_widths
        # Once it ended: one finished bar per started action of its journal.
        _, records = read_journal(journal)
        started = sum(1 for r in records if r["kind"] == "action_started")
        deadline = time.monotonic() + 20  # the viewer's pump folds the last events
        rows = _rows(page)
        while time.monotonic() < deadline and (
            len(rows) != started or any(r["outcome"] == "running" for r in rows)
        ):
            time.sleep(0.1)
            rows = _rows(page)
        assert len(rows) == started
        assert all(r["outcome"] != "running" for r in rows)
    finally:
        page.close()
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=30)
        finally:
            if process.poll() is None:
                process.kill()
                process.wait(timeout=10)
            reader.join(timeout=10)
            if process.stderr is not None:
                process.stderr.close()
    assert errors == []
    assert process.returncode == 0


@pytest.mark.timeout(120)
def test_the_docs_screenshot_tool_draws_the_gantt_of_a_journal(
    browser: Any, journal: Path, tmp_path: Path
) -> None:
    spec = importlib.util.spec_from_file_location("gantt_screenshot", TOOL)
    assert spec is not None and spec.loader is not None
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    out = tmp_path / "gantt.png"
    rows = tool.take(out, journal, browser=browser)
    started = sum(1 for r in read_journal(journal)[1] if r["kind"] == "action_started")
    assert rows == started
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _long_journal(path: Path, actions: int, scale: float = 0.01) -> None:
    """A journal of one temporal plan of ``actions`` actions in three overlapping lanes
    (records as the dispatcher writes them), at time scale ``scale`` (0: the actions
    take a millisecond each)."""
    tree = {"path": "/ROOT", "label": "ROOT", "type": "Executive", "outcomes": ["succeeded"],
            "input_keys": [], "output_keys": [], "is_container": True, "children": [],
            "edges": [], "initial_states": []}  # fmt: skip
    lines = [{"kind": "header", "format": "smach-journal/1", "structure": tree}]
    lines.append({"kind": "container_started", "path": "/ROOT", "time": 10.0})
    lines.append({"kind": "container_started", "path": "/ROOT/PLAN", "time": 10.0})
    for i in range(actions):
        start, duration = (i // 3) * 2.0, 3.0 + i % 3
        label = f"{i + 1:03d}_MOVE_ROBOT{i % 3}_WAYPOINT_WITH_A_LONG_NAME_{i}"
        common = {"path": f"/ROOT/PLAN/{label}", "index": i + 1,
                  "action": f"(move robot{i % 3} waypoint-with-a-long-name-{i} next-{i})",
                  "planned_start": start, "planned_duration": duration}  # fmt: skip
        t0, t1 = 10.0 + start * 0.01, 10.0 + (start + duration * 1.2) * 0.01
        if scale == 0:
            t0, t1 = 10.0 + i * 0.001, 10.0 + i * 0.001 + 0.0008
        lines.append({"kind": "action_started", "time": t0, "actual_start": t0 - 10.0,
                      "time_scale": scale, **common})  # fmt: skip
        lines.append({"kind": "action_ended", "time": t1, "actual_start": t0 - 10.0,
                      "actual_end": t1 - 10.0, "outcome": "succeeded", **common})  # fmt: skip
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))


@pytest.mark.timeout(120)
def test_the_first_view_reaches_the_gantt_script_however_late_it_loads(
    browser: Any, tmp_path: Path
) -> None:
    """A replay gets one view, at the start: the page waits for all its scripts before
    asking for it. It did not, and on a busy machine /api/view could answer before the
    browser had run gantt.js: its button stayed hidden (scene.js and orders.js too)."""
    journal = tmp_path / "long.jsonl"
    _long_journal(journal, 30)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.route("**/static/gantt.js", lambda route: (time.sleep(1.0), route.continue_()))
    with serve(JournalSource(journal), quiet=True) as viewer:
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        page.wait_for_selector("#gantt-toggle:not([hidden])", timeout=10_000)
        assert page.get_attribute("body", "data-gantt-rows") == "30"
    page.close()


@pytest.mark.timeout(120)
def test_a_plan_of_150_actions_scrolls_under_a_fixed_axis_with_readable_labels(
    browser: Any, tmp_path: Path
) -> None:
    journal = tmp_path / "long.jsonl"
    _long_journal(journal, 150)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    with serve(JournalSource(journal), quiet=True) as viewer:
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=10_000)
        page.click("#gantt-toggle")
        page.wait_for_selector("body[data-gantt-drawn='150']")
        scroll = page.eval_on_selector("#gantt-scroll", "e => [e.scrollHeight, e.clientHeight]")
        assert scroll[0] > scroll[1] * 3  # the rows scroll
        axis_before = page.locator("#gantt-axis").bounding_box()
        labels = page.eval_on_selector_all(
            "#gantt-chart text.gantt-label",
            "els => els.map(e => { const b = e.getBBox(); return [b.x, b.y, b.width, b.height]; })",
        )
        assert len(labels) == 150
        for (_, y, _, h), (_, y2, _, _) in itertools.pairwise(labels):
            assert y + h <= y2 + 0.5  # rows do not overlap
        label_column = page.eval_on_selector(
            "#gantt-chart rect.gantt-planned", "e => Number(e.getAttribute('x'))"
        )
        assert all(x + w <= label_column for x, _, w, _ in labels)  # labels clear of bars
        page.eval_on_selector("#gantt-scroll", "e => { e.scrollTop = e.scrollHeight; }")
        last = page.locator("#gantt-chart g.gantt-row[data-index='150']")
        assert last.is_visible()
        box, pane = last.bounding_box(), page.locator("#gantt-scroll").bounding_box()
        assert box is not None and pane is not None
        assert pane["y"] <= box["y"] and box["y"] + box["height"] <= pane["y"] + pane["height"] + 1
        assert page.locator("#gantt-axis").bounding_box() == axis_before  # the axis stays
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "gantt-150.png"))
    page.close()
    assert errors == []


@pytest.mark.timeout(120)
def test_a_run_at_time_scale_zero_gets_a_wall_seconds_axis_under_the_plan_seconds_one(
    browser: Any, tmp_path: Path
) -> None:
    journal = tmp_path / "flat-out.jsonl"
    _long_journal(journal, 12, scale=0.0)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    with serve(JournalSource(journal), quiet=True) as viewer:
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=10_000)
        page.click("#gantt-toggle")
        page.wait_for_selector("body[data-gantt-drawn='12']")
        units = page.eval_on_selector_all(
            "#gantt-axis text.gantt-unit", "els => els.map(e => e.textContent)"
        )
        assert units == ["plan s", "wall s"]
        assert "wall seconds" in page.inner_text("#gantt-note")
        assert "time scale 0" in page.inner_text("#gantt-note")
        rows = _rows(page)
        assert len(rows) == 12 and all(r["planned"] > 0 and r["actual"] > 0 for r in rows)
    page.close()
