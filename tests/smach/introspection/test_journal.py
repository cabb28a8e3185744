"""The JSONL journal: header, one line per event, safe value summaries."""

from __future__ import annotations

import gc
import json
import math
import re
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from smach_helpers import LogRecorder
from viewer_machines import wait_until

import smach
from smach.introspection import events as ev
from smach.introspection.journal import Journal, event_record, read_journal, summarise
from smach.testing import ScriptedState


def chain_of(n: int) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["finished"])
    for i in range(n):
        sm.add(
            f"S{i}",
            ScriptedState(["done"]),
            transitions={"done": f"S{i + 1}" if i + 1 < n else "finished"},
        )
    return sm


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


@pytest.mark.timeout(60)
def test_journal_lines_reach_the_file_while_the_run_goes_on(tmp_path: Path) -> None:
    path = tmp_path / "live.jsonl"
    seen: list[int] = []

    class Peek(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["done"])

        def execute(self, ud: smach.UserData) -> str:
            # No flush, no close: the writer thread gets there on its own.
            wait_until(lambda: len(path.read_text().splitlines()) >= 3, what="lines on disk")
            seen.append(len(path.read_text().splitlines()))
            return "done"

    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("PEEK", Peek())
    with Journal(path, sm):
        sm.execute()
    assert seen == [3]  # header, container_started, state_entered


@pytest.mark.timeout(60)
def test_flush_writes_every_queued_event_before_returning(tmp_path: Path) -> None:
    path = tmp_path / "flush.jsonl"
    seen: list[list[str]] = []
    journal = Journal(path, flush_interval=3600)  # the writer thread never wakes in time

    class Peek(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["done"])

        def execute(self, ud: smach.UserData) -> str:
            journal.flush()
            seen.append([r["kind"] for r in read_journal(path)[1]])
            return "done"

    sm = smach.StateMachine(outcomes=["done"])
    sm.add("PEEK", Peek())
    sm.add_listener(journal)
    sm.execute()
    journal.close()
    assert seen == [["container_started", "state_entered"]]


@pytest.mark.timeout(60)
def test_checkpoint_records_and_the_events_before_them_are_on_disk_when_written(
    tmp_path: Path,
) -> None:
    path = tmp_path / "checkpoints.jsonl"
    journal = Journal(path, flush_interval=3600)
    sm = chain_of(50)
    sm.add_listener(journal)
    state = {"done": [1, 2]}
    sm.execute()
    assert journal.pending > 0  # queued, not written
    journal.write_raw("checkpoint", state=state)
    state["done"].append(3)  # the caller's data changes after the call: not the record
    assert journal.pending == 0
    _, records = read_journal(path)
    assert [r["kind"] for r in records[:2]] == ["container_started", "state_entered"]
    assert records[-2]["kind"] == "container_terminated"
    assert records[-1] == {"kind": "checkpoint", "state": {"done": [1, 2]}}
    sm.execute()
    journal.write_record("summary", steps=50)
    _, records = read_journal(path)
    assert records[-1] == {"kind": "summary", "steps": 50}
    assert [r["kind"] for r in records].count("container_terminated") == 2
    journal.close()


@pytest.mark.timeout(60)
def test_close_writes_everything_in_order(tmp_path: Path) -> None:
    path = tmp_path / "close.jsonl"
    sm = chain_of(1000)
    with Journal(path, sm, flush_interval=3600) as journal:
        sm.execute()
        assert journal.pending > 0
    _, records = read_journal(path)
    entered = [r["label"] for r in records if r["kind"] == "state_entered"]
    assert entered == [f"S{i}" for i in range(1000)]
    assert len(records) == 2 + 3 * 1000 - 1  # started, 1000 x (entered, exited), 999 transitions
    assert records[-1]["kind"] == "container_terminated"


@pytest.mark.timeout(60)
def test_events_of_many_threads_all_land_each_thread_in_order(tmp_path: Path) -> None:
    path = tmp_path / "threads.jsonl"
    machines = [chain_of(300) for _ in range(4)]
    with Journal(path, flush_interval=0.0005) as journal:
        for n, sm in enumerate(machines):
            sm.set_root_path(f"/M{n}")
            sm.add_listener(journal)
        threads = [threading.Thread(target=sm.execute) for sm in machines]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    _, records = read_journal(path)
    for n in range(4):
        mine = [r for r in records if r["path"].startswith(f"/M{n}")]
        assert len(mine) == 2 + 3 * 300 - 1
        labels = [r["label"] for r in mine if r["kind"] == "state_entered"]
        assert labels == [f"S{i}" for i in range(300)]
        assert [r["time"] for r in mine] == sorted(r["time"] for r in mine)


class SlowFile:
    """A file whose writes take a while and are partial (a slow disk)."""

    def __init__(self, file: Any) -> None:
        self.file = file
        self.writes = 0

    def write(self, data: Any) -> int:
        self.writes += 1
        time.sleep(0.005)
        return int(self.file.write(bytes(data[:4000])))  # at most 4000 bytes per call

    def close(self) -> None:
        self.file.close()


@pytest.mark.timeout(60)
def test_a_slow_file_loses_no_event(tmp_path: Path) -> None:
    path = tmp_path / "slow.jsonl"
    sm = chain_of(2000)
    journal = Journal(path, flush_interval=0.0005, max_interval=0.001)
    slow = SlowFile(journal._writer.file)
    journal._writer.file = slow
    sm.add_listener(journal)
    sm.execute()  # never waits for the disk: the queue takes what it cannot write yet
    journal.close()
    _, records = read_journal(path)
    assert len(records) == 2 + 3 * 2000 - 1
    assert [r["label"] for r in records if r["kind"] == "state_exited"] == [
        f"S{i}" for i in range(2000)
    ]
    assert slow.writes > 50
    assert journal.events_written == 2 + 3 * 2000 - 1


@pytest.mark.timeout(60)
def test_mutable_userdata_is_recorded_as_it_was_when_written(tmp_path: Path) -> None:
    class Writes(smach.State):
        def __init__(self) -> None:
            super().__init__(outcomes=["done"], output_keys=["items", "name"])

        def execute(self, ud: smach.UserData) -> str:
            items = [1, 2]
            ud.items = items
            ud.name = "first"
            items.append(3)  # after the event: the journal keeps [1, 2]
            return "done"

    sm = smach.StateMachine(outcomes=["done"])
    sm.add("W", Writes())
    path = tmp_path / "ud.jsonl"
    with Journal(path, sm, flush_interval=3600):
        sm.execute()
    _, records = read_journal(path)
    written = {r["key"]: r["value"] for r in records if r["kind"] == "userdata_written"}
    assert written == {"items": [1, 2], "name": "first"}


def test_lines_are_those_of_json_dumps_of_the_event_record(tmp_path: Path) -> None:
    common = {"time": 12.5, "thread": 'Main "thread"'}
    samples: list[ev.Event] = [
        ev.StateEntered(path="/ROOT/A", label="A", **common),
        ev.StateEntered(path="/ROOT/" + "é" * 300, label="é" * 300, **common),
        ev.StateExited(path="/ROOT/A", label="A", outcome=None, **common),
        ev.StateExited(path="/ROOT/A", label="A", outcome="d\none\n", **common),
        ev.Transition(path="/ROOT", source="A", outcome="x" * 250, target="B", **common),
        ev.Transition(
            path="/ROOT", source="A", outcome="ok", target="B", time=float("inf"), thread="t"
        ),
        ev.StateEntered(path="/ROOT/A", label=7, **common),  # type: ignore[arg-type]
        ev.ContainerStarted(
            path="/ROOT", container_type="StateMachine", initial_states=("A",), **common
        ),
        ev.UserdataWritten(path="/ROOT", key="k", value={"a": [1, None]}, writer="A", **common),
        ev.UserdataWritten(path="/ROOT", key="k", value=float("nan"), writer="A", **common),
        ev.ContainerStarted(
            path="/ROOT",
            container_type="StateMachine",
            initial_states=("A",),
            time=12.75,
            thread="t",
        ),
        ev.ContainerStarted(
            path="/ROOT",
            container_type="StateMachine",
            initial_states=("B",),
            time=13.0,
            thread="t",
        ),
        ev.ContainerTerminated(
            path="/ROOT", terminal_states=("B",), outcome=None, time=13.0, thread="t"
        ),
        ev.ContainerTerminated(
            path="/ROOT", terminal_states=("B",), outcome="done", time=13.0, thread="t"
        ),
        # Same path, other strings: the cached line parts of /ROOT/A must not be reused.
        ev.StateEntered(path="/ROOT/A", label="A", time=13.25, thread="other"),
        ev.StateExited(path="/ROOT/A", label="A", outcome="done", time=13.5, thread="other"),
    ]
    # Steps, as a state machine sends them: (state_exited, transition[, state_entered]).
    pairs = [
        (
            ev.StateExited(path="/ROOT/A", label="A", outcome="go", time=14.0, thread="t"),
            ev.Transition(
                path="/ROOT", source="A", outcome="go", target="B", time=14.0, thread="t"
            ),
        ),
        (  # not a pair the fast path knows: written one by one
            ev.StateExited(path="/ROOT/A", label="A", outcome="go", time=15.0, thread="t"),
            ev.StateEntered(path="/ROOT/B", label="B", time=15.5, thread="t"),
        ),
        (  # a step with the next state entered
            ev.StateExited(path="/ROOT/A", label="A", outcome="go", time=16.0, thread="t"),
            ev.Transition(
                path="/ROOT", source="A", outcome="go", target="B", time=16.0, thread="t"
            ),
            ev.StateEntered(path="/ROOT/B", label="B", time=16.5, thread="t"),
        ),
        (  # the entered state is not the target: one by one
            ev.StateExited(path="/ROOT/A", label="A", outcome="go", time=17.0, thread="t"),
            ev.Transition(
                path="/ROOT", source="A", outcome="go", target="B", time=17.0, thread="t"
            ),
            ev.StateEntered(path="/ROOT/C", label="C", time=17.5, thread="t"),
        ),
    ]
    path = tmp_path / "format.jsonl"
    with Journal(path) as journal:
        for event in samples:
            journal(event)
        for pair in pairs * 2:  # the second time from the cache
            journal.capture_many(tuple(event.capture() for event in pair))
    samples += [event for pair in pairs * 2 for event in pair]
    assert journal.events_written == len(samples)
    lines = path.read_text(encoding="utf-8").splitlines()[1:]
    assert len(lines) == len(samples)
    for line, event in zip(lines, samples, strict=True):
        expected = event_record(event)
        if math.isfinite(event.time):
            expected["time"] = round(event.time, 9)  # times are written to the nanosecond
        got = json.loads(line)
        assert got == expected and list(got) == list(expected)
        # The same text as json.dumps, but for the spelling of the time.
        untimed = re.sub(r'"time": [^,]*', "", line)
        assert untimed == re.sub(
            r'"time": [^,]*', "", json.dumps(expected, ensure_ascii=False, default=str)
        )


def test_a_journal_dropped_without_close_is_written_out(tmp_path: Path) -> None:
    path = tmp_path / "dropped.jsonl"
    sm = chain_of(100)
    journal = Journal(path, flush_interval=3600)
    sm.add_listener(journal)
    sm.execute()
    sm.remove_listener(journal)
    del journal
    gc.collect()
    assert len(read_journal(path)[1]) == 2 + 3 * 100 - 1


@pytest.mark.timeout(60)
def test_interpreter_exit_writes_what_is_queued(tmp_path: Path) -> None:
    path = tmp_path / "exit.jsonl"
    script = f"""
import smach
from smach.introspection.journal import Journal
sm = smach.StateMachine(outcomes=["done"])
for i in range(100):
    sm.add(f"S{{i}}", smach.CBState(lambda ud: "done", outcomes=["done"]),
           transitions={{"done": f"S{{i + 1}}" if i < 99 else "done"}})
journal = Journal({str(path)!r}, sm, flush_interval=3600)
sm.execute()
assert journal.pending > 0
"""
    subprocess.run([sys.executable, "-c", script], check=True, timeout=60)
    assert len(read_journal(path)[1]) == 2 + 3 * 100 - 1


class BrokenFile(SlowFile):
    def write(self, data: Any) -> int:
        raise OSError(28, "No space left on device")


@pytest.mark.timeout(60)
def test_a_failing_disk_detaches_the_journal_and_the_run_goes_on(
    tmp_path: Path, logs: LogRecorder
) -> None:
    sm = chain_of(20)
    journal = Journal(tmp_path / "full.jsonl", sm, flush_interval=0.0005)
    original = journal._writer.file
    journal._writer.file = BrokenFile(original)
    assert sm.execute() == "finished"
    wait_until(lambda: journal not in sm._bus.listeners or journal._writer.error is not None)
    assert sm.execute() == "finished"
    assert journal not in sm._bus.listeners
    assert any("No space left" in line for line in logs.error)
    with pytest.raises(OSError, match="No space"):
        journal.write_raw("checkpoint", state={})
    journal.close()
    original.close()


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
