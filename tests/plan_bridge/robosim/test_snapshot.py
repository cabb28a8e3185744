"""`plan-bridge run WORLD --snapshot FILE`: the picture of a pyrobosim run."""

from __future__ import annotations

import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main
from plan_bridge.robosim.loading import load_world_file
from plan_bridge.robosim.skills import skill_for
from plan_bridge.robosim.world import RobosimWorld

ROOT = Path(__file__).resolve().parents[3]
FETCH = ROOT / "domains" / "robosim_fetch"
CLOSE = FETCH / "events" / "close_hallway.yaml"
SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def picture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The SVG of the repository's mission with the hallway closing on the way."""
    path = tmp_path_factory.mktemp("snapshot") / "run.svg"
    args = ["run", str(FETCH), "--events", str(CLOSE), "--snapshot", str(path), "--quiet"]
    assert main(args) == 0
    return path


def _by_class(root: ET.Element, tag: str, kind: str) -> list[ET.Element]:
    return [e for e in root.iter(SVG + tag) if kind in e.get("class", "").split()]


def test_the_svg_is_xml_with_one_element_per_room_hallway_and_robot_path(picture: Path) -> None:
    root = ET.parse(picture).getroot()  # well-formed, or this raises
    assert root.tag == SVG + "svg"
    sim = load_world_file(FETCH / "world.yaml")
    rooms = _by_class(root, "polygon", "room")
    halls = _by_class(root, "polygon", "hallway")
    assert sorted(e.get("data-name", "") for e in rooms) == sorted(r.name for r in sim.rooms)
    assert sorted(e.get("data-name", "") for e in halls) == sorted(h.name for h in sim.hallways)
    assert len(_by_class(root, "path", "trail")) == len(sim.robots) == 1
    assert len(_by_class(root, "g", "robot")) == 1
    spawns = {e.get("data-name") for e in _by_class(root, "polygon", "spawn")}
    assert {"fridge_shelf", "coffee_table_tabletop"} <= spawns
    # The soda is on the coffee table at the end.
    assert "soda" in {e.get("data-name") for e in _by_class(root, "circle", "object")}
    title = " ".join(t.text or "" for t in _by_class(root, "text", "title"))
    assert "robosim_fetch" in title and "succeeded" in title
    assert re.search(r"\d+\.\d s simulated \| \d+\.\d m driven", title)


def test_the_closed_hallway_is_marked_closed_and_locked(picture: Path) -> None:
    root = ET.parse(picture).getroot()
    closed = {
        e.get("data-name"): e.get("class", "").split() for e in _by_class(root, "polygon", "closed")
    }
    assert closed == {"hall_kitchen_living_room": ["hallway", "closed", "locked"]}


def test_the_path_driven_stays_inside_the_world(picture: Path) -> None:
    root = ET.parse(picture).getroot()
    (trail,) = _by_class(root, "path", "trail")
    numbers = [float(n) for n in re.findall(r"-?\d+(?:\.\d+)?", trail.get("d", ""))]
    points = list(zip(numbers[::2], numbers[1::2], strict=True))
    assert len(points) > 10
    sim = load_world_file(FETCH / "world.yaml")
    (x0, x1), (y0, y1) = sim.x_bounds, sim.y_bounds
    assert all(x0 <= x <= x1 and y0 <= y <= y1 for x, y in points)
    # It went through the office (the detour): the office's y is above the rooms'.
    office = sim.get_room_by_name("office").polygon.bounds
    assert any(office[1] <= y <= office[3] for _, y in points)


def test_a_png_is_written_through_matplotlib(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("matplotlib", reason="matplotlib is not installed")
    path = tmp_path / "route.png"
    args = ["run", str(FETCH), "--goal", "(At robot office)", "--fail-rate", "0"]
    assert main([*args, "--snapshot", str(path)]) == 0
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"picture: {path.resolve()}" in capsys.readouterr().err.splitlines()


def test_a_png_without_matplotlib_is_refused_naming_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib fails
    assert main(["run", str(FETCH), "--snapshot", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "matplotlib" in err and ".svg" in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    ("target", "name", "expected"),
    [
        (ROOT / "domains" / "fetch_drink", "x.svg", "pyrobosim worlds only"),
        (FETCH, "x.jpg", "give a .svg or .png file"),
    ],
)
def test_a_snapshot_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], target: Path, name: str, expected: str
) -> None:
    assert main(["run", str(target), "--snapshot", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err and len(err.splitlines()) == 1
    assert not (tmp_path / name).exists()


def test_trails_are_kept_in_the_world_snapshot(test_world_file: Path) -> None:
    world = RobosimWorld(test_world_file, seed=1)
    assert (
        skill_for(world, "navigate", "robot", "kitchen", "table0_tabletop").execute() == "succeeded"
    )
    (trail,) = world.trails["robot"]
    assert len(trail) >= 2
    saved = world.snapshot()
    other = RobosimWorld(test_world_file, seed=1)
    other.restore(saved)
    assert other.trails == world.trails
    # A snapshot written before trails were recorded: they start empty.
    older = {k: v for k, v in saved.items() if k != "trails"}
    other.restore(older)
    assert other.trails == {"robot": []}


def test_a_trail_keeps_the_newest_poses_of_a_long_day(test_world_file: Path) -> None:
    from types import SimpleNamespace

    from plan_bridge.robosim.world import TRAIL_POINTS

    world = RobosimWorld(test_world_file, seed=1)
    robot = SimpleNamespace(name="robot")
    for leg in range(TRAIL_POINTS // 50 + 10):  # legs of 100 poses, each apart from the last
        start = leg * 1000.0
        world.record_drive(robot, [SimpleNamespace(x=start + i, y=0.0) for i in range(100)])
    parts = world.trails["robot"]
    assert sum(len(part) for part in parts) == TRAIL_POINTS
    assert parts[-1][-1] == [start + 99, 0.0]  # the newest pose is kept
    assert all(len(part) >= 2 for part in parts)
