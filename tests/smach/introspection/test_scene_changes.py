"""Scenes in a journal are written as the lines that changed, and read back whole."""

from __future__ import annotations

from pathlib import Path

import smach
from smach.events import SceneChanged
from smach.introspection.journal import Journal, read_journal
from smach.introspection.scene_changes import WHOLE_EVERY, SceneChanges, SceneText
from smach.introspection.source import JournalSource
from smach.summary import Summary


def drawing(robot_x: int, trail: int) -> str:
    """A picture one element a line: a big map, a robot, a trail that grows."""
    rooms = [f'<polygon class="room" points="{i},0 {i + 1},0 {i + 1},1"/>' for i in range(300)]
    line = " L ".join(f"{x} 0" for x in range(trail))
    return "\n".join(
        [
            "<svg>",
            *rooms,
            f'<path class="trail" d="M {line}"/>',
            f'<circle cx="{robot_x}"/>',
            "</svg>",
        ]
    )


def scene(svg: str, n: int) -> tuple[object, ...]:
    return (SceneChanged, "/ROOT", float(n), "t", Summary(svg), f"scene {n}")


def test_a_scene_is_written_as_its_changed_lines_and_read_back_whole() -> None:
    writer, reader = SceneChanges(), SceneText()
    pictures = [drawing(x, 3 + x) for x in range(5)]
    written = [writer.capture(scene(svg, n)) for n, svg in enumerate(pictures)]
    assert written[0][0] is SceneChanged  # the first one whole
    assert all(item[0] is not SceneChanged for item in written[1:])
    change = written[1][4].value
    assert sum(len(lines) for _, _, lines in change) == 2  # the trail and the robot
    records = [
        {"kind": "scene", "svg": item[4].value}
        if item[0] is SceneChanged
        else {"kind": "scene", "svg_change": item[4].value}
        for item in written
    ]
    assert [reader.record(r)["svg"] for r in records] == pictures


def test_every_hundredth_scene_is_written_whole() -> None:
    writer = SceneChanges()
    kinds = [writer.capture(scene(drawing(n, 2), n))[0] for n in range(2 * WHOLE_EVERY + 1)]
    whole = [n for n, kind in enumerate(kinds) if kind is SceneChanged]
    assert whole == [0, WHOLE_EVERY, 2 * WHOLE_EVERY]


def test_a_journal_of_scenes_is_small_and_every_reader_gets_the_pictures_whole(
    tmp_path: Path,
) -> None:
    root = smach.StateMachine(outcomes=["done"])
    pictures = [drawing(x, 10 + 5 * x) for x in range(30)]

    def show(ud: smach.UserData) -> str:
        for n, svg in enumerate(pictures):
            smach.introspection.events.publish(
                root, SceneChanged(path="/ROOT", time=float(n), thread="t", svg=svg)
            )
        return "done"

    root.add("SHOW", smach.CBState(show, outcomes=["done"]), transitions={"done": "done"})
    path = tmp_path / "run.jsonl"
    with Journal(path, root):
        assert root.execute() == "done"
    _, records = read_journal(path)
    assert [r["svg"] for r in records if r["kind"] == "scene"] == pictures
    source = JournalSource(path)
    assert [r["svg"] for r in source.poll() if r["kind"] == "scene"] == pictures
    source.close()
    assert path.stat().st_size < sum(len(svg) for svg in pictures) / 10


def test_an_appended_journal_writes_its_first_scene_whole(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    root = smach.StateMachine(outcomes=["done"])
    root.add("X", smach.CBState(lambda ud: "done", outcomes=["done"]), transitions={"done": "done"})
    for first in (0, 1):
        with Journal(path, root, append=bool(first)):
            for n in range(3):
                smach.introspection.events.publish(
                    root,
                    SceneChanged(
                        path="/ROOT", time=float(n), thread="t", svg=drawing(n + first, 4)
                    ),
                )
            root.execute()
    lines = path.read_text().splitlines()
    scenes = [line for line in lines if '"kind": "scene"' in line]
    assert ['"svg":' in line for line in scenes] == [True, False, False, True, False, False]
    _, records = read_journal(path)
    got = [r["svg"] for r in records if r["kind"] == "scene"]
    assert got == [drawing(n + first, 4) for first in (0, 1) for n in range(3)]
