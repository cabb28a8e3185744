"""``scene`` records: a picture of the world beside the machine (SceneChanged).

The fold keeps the newest scene at every moment (replay shows the scene of the moment),
journals keep the SVG whole, and the viewer sends a picture only by its number.
"""

from __future__ import annotations

import http.client
import json
import threading
from pathlib import Path
from typing import Any

import pytest
from viewer_machines import wait_until

import smach
from smach.introspection import JournalSource, serve
from smach.introspection.events import SceneChanged, captured, publish, stamp
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import Journal, read_journal
from smach.introspection.model import History, ViewModel, fold
from smach.introspection.summary import MAX_REPR


def picture(label: str, size: int = 600) -> str:
    """A standalone SVG longer than MAX_REPR (records must not cut it)."""
    pad = "".join(f'<rect x="{i}" y="0" width="1" height="1"/>' for i in range(size // 40))
    return (
        '<svg xmlns="http://www.w3.org/2000/svg" width="120" height="40">'
        f'<text x="4" y="20" data-label="{label}">{label}</text>{pad}</svg>'
    )


def scene_record(label: str, time: float, path: str = "/ROOT") -> dict[str, Any]:
    return {
        "kind": "scene",
        "path": path,
        "time": time,
        "thread": "MainThread",
        "svg": picture(label),
        "title": f"moment {label}",
    }


def entered(path: str, time: float) -> dict[str, Any]:
    label = path.rsplit("/", 1)[1]
    return {"kind": "state_entered", "path": path, "time": time, "label": label}


def test_a_scene_record_folds_into_the_view_and_its_json_carries_no_svg() -> None:
    model = ViewModel()
    model.apply(entered("/ROOT/A", 1.0))
    record = scene_record("first", 2.0)
    model.apply(record)
    assert model.scene is not None
    assert model.scene["svg"] is record["svg"]  # shared, not copied
    assert model.scene["n"] == 2 and model.scene["title"] == "moment first"
    data = model.to_json()
    assert data["scene"] == {
        "n": 2,
        "time": 2.0,
        "title": "moment first",
        "path": "/ROOT",
        "bytes": len(record["svg"]),
    }
    assert "<svg" not in json.dumps(data)
    # A copy keeps the scene; folding more into the copy leaves the original alone.
    copy = model.copy()
    copy.apply(scene_record("second", 3.0))
    assert model.scene["title"] == "moment first"
    assert copy.scene is not None and copy.scene["title"] == "moment second"


def test_a_scene_record_without_svg_text_leaves_the_scene_as_it_was() -> None:
    model = ViewModel()
    model.apply(scene_record("first", 1.0))
    model.apply({"kind": "scene", "path": "/ROOT", "time": 2.0, "svg": ""})
    model.apply({"kind": "scene", "path": "/ROOT", "time": 3.0, "svg": {"not": "text"}})
    assert model.scene is not None and model.scene["title"] == "moment first"
    assert model.index == 3
    assert ViewModel().to_json()["scene"] is None


def test_replay_at_an_earlier_moment_shows_the_scene_of_that_moment() -> None:
    records = [
        entered("/ROOT/A", 1.0),
        scene_record("start", 1.5),
        entered("/ROOT/B", 2.0),
        entered("/ROOT/C", 3.0),
        scene_record("middle", 3.5),
        entered("/ROOT/D", 4.0),
        scene_record("end", 5.0),
    ]
    history = History({}, every=2)  # checkpoints between the scenes
    for record in records:
        history.add(record)

    def title_at(n: int) -> str | None:
        scene = history.view_at(n).scene
        return None if scene is None else str(scene["title"])

    assert [title_at(n) for n in range(len(records) + 1)] == [
        None,
        None,
        "moment start",
        "moment start",
        "moment start",
        "moment middle",
        "moment middle",
        "moment end",
    ]
    # The fold of a journal up to a moment agrees with the history's views.
    for n in range(len(records) + 1):
        assert fold({}, records, n).scene == history.view_at(n).scene
    assert history.view_at(4).scene == history.view_at(2).scene
    assert history.view_at(5).to_json()["scene"]["n"] == 5


class Drives(smach.State):
    """Publishes a picture of its 'world' after each of its drives."""

    def __init__(self, owner: list[smach.State]) -> None:
        super().__init__(outcomes=["done"])
        self.owner = owner

    def execute(self, ud: smach.UserData) -> str:
        for leg in range(3):
            t, thread = stamp()
            event = SceneChanged(
                path=self.owner[0].path, time=t, thread=thread, svg=picture(f"leg{leg}"),
                title=f"leg {leg}",
            )  # fmt: skip
            publish(self.owner[0], event)
        return "done"


class Hold(smach.State):
    """Waits for ``gate`` (a live run to look at)."""

    def __init__(self, gate: threading.Event) -> None:
        super().__init__(outcomes=["done"])
        self.gate = gate

    def execute(self, ud: smach.UserData) -> str:
        self.gate.wait(10)
        return "done"


def world_machine(gate: threading.Event | None = None) -> smach.StateMachine:
    """DRIVE -> ARRIVE (three pictures each), then HOLD until ``gate`` if given."""
    owner: list[smach.State] = []
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("DRIVE", Drives(owner), transitions={"done": "ARRIVE"})
        smach.StateMachine.add(
            "ARRIVE", Drives(owner), transitions={"done": "HOLD" if gate else "done"}
        )
        if gate is not None:
            smach.StateMachine.add("HOLD", Hold(gate), transitions={"done": "done"})
    owner.append(sm)
    return sm


def test_a_journal_keeps_the_pictures_whole_and_replays_them_in_order(tmp_path: Path) -> None:
    sm = world_machine()
    assert not captured(sm)
    publish(sm, SceneChanged(path="/ROOT", time=0.0, thread="t", svg=picture("nobody")))
    path = tmp_path / "world.jsonl"
    with Journal(path, sm):
        assert captured(sm)
        assert sm.execute() == "done"
    header, records = read_journal(path)
    scenes = [r for r in records if r["kind"] == "scene"]
    assert [r["title"] for r in scenes] == [f"leg {i}" for i in (0, 1, 2, 0, 1, 2)]
    assert all(r["svg"] == picture(r["svg"].split('data-label="')[1].split('"')[0]) for r in scenes)
    assert all(len(r["svg"]) > MAX_REPR for r in scenes)
    assert all(r["path"] == "/ROOT" for r in scenes)
    # Journals with scenes stay faithful and replayable (``view --check``).
    assert journal_problems(path) == []
    last = fold(header, records).scene
    assert last is not None and 'data-label="leg2"' in last["svg"]


def http_get(viewer: Any, path: str) -> tuple[int, str, str, str]:
    conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
    conn.request("GET", path)
    response = conn.getresponse()
    body = response.read().decode("utf-8")
    conn.close()
    policy = response.getheader("Content-Security-Policy") or ""
    return response.status, response.getheader("Content-Type") or "", policy, body


@pytest.mark.timeout(30)
def test_the_viewer_sends_the_view_with_the_scene_number_and_the_picture_on_request(
    tmp_path: Path,
) -> None:
    sm = world_machine()
    path = tmp_path / "world.jsonl"
    with Journal(path, sm):
        sm.execute()
    with serve(JournalSource(path), quiet=True) as viewer:
        status, _, _, body = http_get(viewer, "/api/view")
        view = json.loads(body)
        assert status == 200 and view["has_scenes"] is True
        assert view["scene"]["title"] == "leg 2" and "<svg" not in body
        n = view["scene"]["n"]
        status, kind, policy, svg = http_get(viewer, f"/api/scene?n={n}")
        assert status == 200 and kind.startswith("image/svg+xml")
        assert 'data-label="leg2"' in svg and "sandbox" in policy
        # Replay: the first scene's moment, and before any scene.
        _, records = read_journal(path)
        first = next(i for i, r in enumerate(records) if r["kind"] == "scene") + 1
        early = json.loads(http_get(viewer, f"/api/view?at={first}")[3])
        assert early["scene"]["n"] == first and early["has_scenes"] is True
        assert 'data-label="leg0"' in http_get(viewer, f"/api/scene?n={first}")[3]
        assert json.loads(http_get(viewer, "/api/view?at=1")[3])["scene"] is None
        assert http_get(viewer, "/api/scene?n=1")[0] == 404
        # The timeline's records name the picture's size, not its text.
        listed = json.loads(http_get(viewer, f"/api/records?start=0&end={len(records)}")[3])
        shown = [r for r in listed if r["kind"] == "scene"]
        assert len(shown) == 6 and all("svg" not in r and r["svg_bytes"] > MAX_REPR for r in shown)


@pytest.mark.timeout(30)
def test_a_live_viewer_shows_the_newest_scene_and_streams_no_svg() -> None:
    gate = threading.Event()
    sm = world_machine(gate)
    with serve(sm, quiet=True, interval=0.02) as viewer:

        def newest() -> str:
            return str((json.loads(viewer.view_json()).get("scene") or {}).get("title"))

        runner = threading.Thread(target=sm.execute, daemon=True)
        runner.start()
        try:
            wait_until(lambda: newest() == "leg 2", 10, "the newest scene in the live view")
            view = json.loads(viewer.view_json())
            assert view["has_scenes"] and view["running"]
            assert 'data-label="leg2"' in (viewer.scene_svg(view["scene"]["n"]) or "")
            assert all("svg" not in r for r in viewer.records(0, viewer.history.total))
        finally:
            gate.set()
            runner.join(10)
