"""The pyrobosim map beside the state machine: ``scene`` events of a robosim run.

A journaled (or watched) run of a pyrobosim world carries a picture of the world at the
start, after every step that changed what it shows and after every world event; replay
shows the picture of the moment. The browser parts run in headless Chromium (Playwright,
Debian's chromium) and are skipped when either is missing; screenshots go to
artifacts/viewer/ (gitignored).
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main
from plan_bridge.execution.events import WorldScenes
from plan_bridge.missions.mission import load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from smach.introspection import JournalSource, serve
from smach.introspection.journal import read_journal
from smach.introspection.model import History

ROOT = Path(__file__).resolve().parents[3]
FETCH = ROOT / "domains" / "robosim_fetch"
CLOSE = FETCH / "events" / "close_hallway.yaml"
ARTIFACTS = ROOT / "artifacts" / "viewer"
SVG = "{http://www.w3.org/2000/svg}"
HALL = "hall_kitchen_living_room"


@pytest.fixture(scope="module")
def journal(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """robosim_fetch, seed 1, fail rate 0.2, the kitchen hallway closing on the way."""
    path = tmp_path_factory.mktemp("map") / "run.jsonl"
    args = ["run", str(FETCH), "--journal", str(path), "--fail-rate", "0.2", "--seed", "1"]
    assert main([*args, "--events", str(CLOSE), "--quiet"]) == 0
    return path


def numbered_scenes(journal: Path) -> list[tuple[int, dict[str, Any]]]:
    """(index of the record in the journal, record) of every scene."""
    _, records = read_journal(journal)
    return [(n, r) for n, r in enumerate(records) if r["kind"] == "scene"]


def trail_points(svg: str) -> int:
    root = ET.fromstring(svg)  # well-formed, or this raises
    paths = [e for e in root.iter(SVG + "path") if "trail" in e.get("class", "").split()]
    assert len(paths) == 1  # the one robot
    return sum(1 for word in (paths[0].get("d") or "").split() if word in ("M", "L"))


def robot_xy(svg: str) -> tuple[float, float]:
    root = ET.fromstring(svg)
    robot = next(e for e in root.iter(SVG + "g") if "robot" in e.get("class", "").split())
    disc = robot.find(SVG + "circle")
    assert disc is not None
    return float(disc.get("cx", "0")), float(disc.get("cy", "0"))


def hallway_classes(svg: str, name: str) -> set[str]:
    root = ET.fromstring(svg)
    hall = next(e for e in root.iter(SVG + "polygon") if e.get("data-name") == name)
    return set(hall.get("class", "").split())


def test_the_journal_has_a_picture_at_the_start_and_after_every_drive(journal: Path) -> None:
    _, records = read_journal(journal)
    scenes = numbered_scenes(journal)
    first_step = next(n for n, r in enumerate(records) if r["kind"] == "step_finished")
    start = scenes[0]
    assert start[0] < first_step and start[1]["title"].endswith("· start")
    assert start[1]["path"] == "/ROOT" and trail_points(start[1]["svg"]) == 0
    # A drive that succeeded moved the robot: the picture of its end follows its step_finished.
    drives = [
        n
        for n, r in enumerate(records)
        if r["kind"] == "step_finished"
        and r["outcome"] == "succeeded"
        and r["action"].startswith(("(navigate", "(cross"))
    ]
    assert len(drives) >= 3
    for n in drives:
        after = records[n + 1]
        assert after["kind"] == "scene", (records[n], after["kind"])
        assert f"after step {records[n]['index']} {records[n]['action']}" in after["title"]
    # No picture repeats the one before it (a step that changed nothing visible: none).
    texts = [r["svg"] for _, r in scenes]
    assert all(a != b for a, b in itertools.pairwise(texts))
    assert len(scenes) < len([r for r in records if r["kind"] == "step_finished"]) + 3


def test_the_robots_trail_grows_from_picture_to_picture(journal: Path) -> None:
    scenes = [r for _, r in numbered_scenes(journal)]
    points = [trail_points(r["svg"]) for r in scenes]
    assert points == sorted(points) and points[-1] > points[1] > points[0] == 0
    drives = [r for r in scenes if "(navigate" in r["title"] or "(cross" in r["title"]]
    grown = [trail_points(r["svg"]) for r in drives]
    assert all(b > a for a, b in itertools.pairwise(grown))  # every drive adds
    # Each drive moved the robot from where the picture before it showed it.
    moved = [
        robot_xy(b["svg"]) != robot_xy(a["svg"])
        for a, b in itertools.pairwise(scenes)
        if b in drives
    ]
    assert len(moved) == len(drives) and all(moved)
    # Each picture's caption gives the simulated time, growing.
    seconds = [float(r["title"].split(" s simulated")[0]) for r in scenes]
    assert seconds == sorted(seconds) and seconds[-1] > 30


def test_the_hallway_event_has_its_own_picture_with_the_hallway_closed(journal: Path) -> None:
    scenes = [r for _, r in numbered_scenes(journal)]
    closing = next(i for i, r in enumerate(scenes) if f"{HALL} closed" in r["title"])
    assert "closed" not in hallway_classes(scenes[closing - 1]["svg"], HALL)
    assert {"closed", "locked"} <= hallway_classes(scenes[closing]["svg"], HALL)
    assert all("closed" in hallway_classes(r["svg"], HALL) for r in scenes[closing:])


def test_replay_at_any_moment_shows_the_picture_of_that_moment(journal: Path) -> None:
    header, records = read_journal(journal)
    history = History(header)
    for record in records:
        history.add(record)
    scenes = numbered_scenes(journal)
    for (n, record), nxt in zip(scenes, [*scenes[1:], (len(records), None)], strict=True):
        for at in (n + 1, (n + 1 + nxt[0]) // 2, nxt[0]):
            shown = history.view_at(at).scene
            assert shown is not None and shown["n"] == n + 1 and shown["svg"] == record["svg"]
    assert history.view_at(scenes[0][0]).scene is None
    assert main(["view", "--check", str(journal)]) == 0  # journals with scenes replay exactly


def test_pictures_are_drawn_only_when_a_journal_or_a_viewer_watches(tmp_path: Path) -> None:
    mission = prepare_mission(load_target(FETCH), MissionOptions(seed=1))
    try:
        assert WorldScenes.start(mission.executive, mission.world) is None
        journal = mission.record(str(tmp_path / "watched.jsonl"), header={})
        scenes = WorldScenes.start(mission.executive, mission.world)
        assert scenes is not None and scenes.shown == 1  # the start
        assert scenes.show("again") is False  # the same picture is not sent twice
        scenes.close()
        assert getattr(mission.world, "on_scene", "missing") is None
        journal.close()
    finally:
        mission.world.close()  # type: ignore[union-attr]
    _, records = read_journal(tmp_path / "watched.jsonl")
    assert [r["kind"] for r in records] == ["scene"]


# -- in the browser -------------------------------------------------------------------------
def picture_width(page: Any) -> int:
    return int(page.eval_on_selector("#scene-img", "img => img.complete ? img.naturalWidth : 0"))


@pytest.mark.browser
@pytest.mark.timeout(120)
def test_the_replay_page_shows_the_map_of_the_moment_beside_the_machine(
    browser: Any, journal: Path
) -> None:
    scenes = numbered_scenes(journal)
    last = scenes[-1][0] + 1
    page = browser.new_page(viewport={"width": 1600, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    with serve(JournalSource(journal), quiet=True) as viewer:
        page.goto(viewer.url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        page.wait_for_selector(f"body[data-scene='{last}']", timeout=20_000)
        assert page.is_visible("#scene-pane") and page.is_visible("#scene-img")
        assert page.eval_on_selector("main", "m => m.classList.contains('with-scene')")
        assert picture_width(page) > 300
        graph = page.eval_on_selector("#graph-pane", "e => e.getBoundingClientRect().width")
        assert graph > 300  # the machine keeps its room beside the map
        assert "m driven" in page.inner_text("#scene-caption")
        # The timeline lists the pictures (their size, not their text).
        assert page.locator("#events tr[data-kind='scene']").count() >= 1
        # The moment the hallway closed, the robot on its way (docs/images/viewer-world-map.png).
        event = next(n for n, r in scenes if f"{HALL} closed" in r["title"]) + 1
        page.fill("#slider", str(event))
        page.wait_for_selector(f"body[data-scene='{event}']", timeout=10_000)
        assert "closed" in page.inner_text("#scene-caption")
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "world-map-replay.png"))
        # The slider at the second picture's moment: that picture.
        second = scenes[1][0] + 1
        page.fill("#slider", str(second))
        page.wait_for_selector(f"body[data-index='{second}']", timeout=10_000)
        page.wait_for_selector(f"body[data-scene='{second}']", timeout=10_000)
        assert picture_width(page) > 300
        # Before the first picture: the panel stays, saying there is none yet.
        page.fill("#slider", "0")
        page.wait_for_selector("body[data-scene='0']", timeout=10_000)
        assert page.is_visible("#scene-empty") and page.is_hidden("#scene-img")
        # The World button closes the panel; the graph takes the room back.
        page.click("#scene-toggle")
        assert page.is_hidden("#scene-pane")
        assert not page.eval_on_selector("main", "m => m.classList.contains('with-scene')")
    page.close()
    assert errors == []


@pytest.mark.browser
@pytest.mark.timeout(180)
def test_the_live_page_redraws_the_map_as_the_robot_drives(browser: Any) -> None:
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "plan_bridge", "run", str(FETCH), "--viewer",
         "--time-scale", "0.03", "--control", "--start-paused"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    lines: list[str] = []
    reader = threading.Thread(
        target=lambda: lines.extend(line.rstrip("\n") for line in process.stderr or ()),
        daemon=True,
    )
    reader.start()

    def line(start: str) -> str:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            found = next((x for x in lines if x.startswith(start)), None)
            if found is not None:
                return found.split(": ", 1)[1].strip()
            assert process.poll() is None, "\n".join(lines)
            time.sleep(0.05)
        raise AssertionError(f"no {start!r} line in:\n" + "\n".join(lines))

    page = browser.new_page(viewport={"width": 1600, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    seen: list[str] = []
    try:
        url, control = line("smach viewer: "), line("control: ")
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=20_000)
        # The picture of the start is there before the mission moves.
        page.wait_for_selector("#scene-img:not([hidden])", timeout=20_000)
        assert main(["control", control, "resume"]) == 0
        deadline = time.monotonic() + 120
        while not any(x.startswith("viewer: ") for x in lines):
            shown = page.get_attribute("body", "data-scene")
            if shown and shown != "0" and (not seen or seen[-1] != shown):
                seen.append(shown)
            assert time.monotonic() < deadline and process.poll() is None, "\n".join(lines)
            time.sleep(0.05)
        page.wait_for_selector("#status.succeeded", timeout=20_000)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "world-map-live.png"))
    finally:
        page.close()
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        process.wait(timeout=30)
        reader.join(timeout=10)
        if process.stderr is not None:
            process.stderr.close()
    # While the robot drove, the page showed one new picture after another.
    assert len(seen) >= 5, seen
    assert [int(n) for n in seen] == sorted(int(n) for n in seen)
    assert errors == []
