"""The JSONL journal: header, one line per event, safe value summaries."""

from __future__ import annotations

import json
from pathlib import Path

import smach
from smach.introspection.journal import Journal, read_journal, summarise
from smach.testing import ScriptedState


class Unprintable:
    def __repr__(self) -> str:
        raise RuntimeError("no repr")


def test_journal_header_holds_the_structure_and_caller_fields(tmp_path: Path) -> None:
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", ScriptedState(["done"], output_keys=["x"], writes={"x": 1}))
    path = tmp_path / "run.jsonl"
    with Journal(path, sm, header={"seed": 7}):
        sm.execute()
    header, records = read_journal(path)
    assert header["format"] == "smach-journal/1" and header["seed"] == 7
    assert header["structure"]["children"][0]["path"] == "/ROOT/A"
    kinds = [r["kind"] for r in records]
    assert kinds == [
        "container_started",
        "state_entered",
        "userdata_written",
        "state_exited",
        "container_terminated",
    ]
    assert records[2]["key"] == "x" and records[2]["value"] == 1


def test_journal_lines_are_flushed_as_they_happen(tmp_path: Path) -> None:
    path = tmp_path / "live.jsonl"
    seen: list[int] = []

    class Peek(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["done"])

        def execute(self, ud: smach.UserData) -> str:
            seen.append(len(path.read_text().splitlines()))
            return "done"

    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("PEEK", Peek())
    with Journal(path, sm):
        sm.execute()
    assert seen == [3]  # header, container_started, state_entered already on disk


def test_summaries_are_bounded_json_and_never_fail() -> None:
    value = {
        "long": "x" * 1000,
        "many": list(range(100)),
        "deep": [[[[["bottom"]]]]],
        "odd": Unprintable(),
    }
    summary = summarise(value)
    json.dumps(summary)
    assert len(summary["long"]) <= 201
    assert summary["many"][-1] == "… 80 more"
    assert "repr failed" in summary["odd"]
    assert summarise(float("nan")) == "nan"


def test_a_torn_last_line_from_a_crash_is_ignored(tmp_path: Path) -> None:
    path = tmp_path / "torn.jsonl"
    path.write_text(
        '{"kind": "header", "format": "smach-journal/1"}\n{"kind": "transition"}\n{"kind": "sta'
    )
    header, records = read_journal(path)
    assert header["format"] == "smach-journal/1"
    assert records == [{"kind": "transition"}]
