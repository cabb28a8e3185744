"""The journal: every event of a run as JSON lines, written by a background thread.

The first line is a header (format version, structure snapshot, library version,
and whatever the caller adds, e.g. the seed), so a run can be replayed. Each later
line is one event. Values (userdata) are written as bounded, safe summaries: never
pickled, ``repr`` truncated, containers cut to a few items.

What the executing thread pays: the journal is a
:class:`~smach.introspection.events.CaptureListener` whose batch function is the
``append`` of a queue, so a state machine's step costs the thread that emits it one C
call on a tuple (values that may still change, such as a userdata list, are
summarised into the capture when the event happens, so the record shows the value as
it was). Single events go through :class:`~.journal_structures.MachineTracker`,
which queues the tree of a container that starts for the first time (a new plan) as
a ``structure`` record before its start. A writer thread
(:mod:`~smach.introspection.journal_writer`) wakes every few milliseconds, formats the
queued events as JSON lines (:mod:`~smach.introspection.journal_lines`) and writes
each batch with one system call.

Records a resume needs (checkpoints) are written with :meth:`Journal.write_state`:
the first one whole, the next ones as changes (:mod:`smach.introspection.delta`),
a whole one every :data:`FULL_EVERY`; :func:`read_states` gives them back whole.

Durability contract (it replaces "flushed per event"):

* an event reaches the file (the operating system's cache: it survives a crash of
  the process, not of the machine) within about ``max_interval`` (20 ms) plus one
  switch of the interpreter lock (up to 5 ms when the machine keeps it busy): the
  writer polls every ``flush_interval`` (5 ms) while events come in small batches,
  up to every ``max_interval`` while they come in large ones or none come at all;
* :meth:`Journal.write_record`, :meth:`Journal.write_raw` (checkpoints),
  :meth:`Journal.flush` and :meth:`Journal.close` write every queued event and the
  record before they return, in order, in the calling thread: what a resume needs is
  on disk when the call returns;
* ``close()``, leaving the ``with`` block, garbage collection of the journal and
  interpreter exit write everything still queued;
* nothing is dropped and the executing thread never waits for the disk: the queue
  is unbounded. A disk slower than the events lets it grow (about 100 bytes per
  event) until the disk catches up; the next checkpoint or ``flush()`` waits for it;
* a process killed mid-batch leaves at most a torn last line, which
  :func:`read_journal` skips and ``Journal(..., append=True)`` cuts.

Structure records: see :mod:`smach.introspection.journal_structures` (each machine
once, when it starts, read in the thread that starts it).
"""

from __future__ import annotations

import json
import os
import threading
import weakref
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from smach.introspection.delta import diff, patch
from smach.introspection.events import CaptureListener
from smach.introspection.journal_lines import ENCODER, capture_record, event_record
from smach.introspection.journal_structures import MachineTracker
from smach.introspection.journal_writer import JournalWriter
from smach.introspection.scene_changes import SceneText
from smach.introspection.structure import snapshot
from smach.introspection.summary import MAX_DEPTH, MAX_ITEMS, MAX_REPR, summarise
from smach.state import State

__all__ = [
    "FORMAT",
    "FULL_EVERY",
    "MAX_DEPTH",
    "MAX_ITEMS",
    "MAX_REPR",
    "Journal",
    "capture_record",
    "drop_torn_line",
    "event_record",
    "read_journal",
    "read_states",
    "summarise",
]

FORMAT = "smach-journal/1"
FULL_EVERY = 1000
"""Every this many :meth:`Journal.write_state` records of a kind, one is written whole."""


class Journal(CaptureListener):
    """A listener writing JSON lines; use as ``with Journal(path, root): root.execute()``.

    ``flush_interval`` and ``max_interval`` (seconds) bound how often the writer
    thread looks for queued events: see the module documentation for the durability
    contract. Attach it to a tree by passing ``root``, or with ``add_listener``.
    ``header`` entries are summarised like events' values (long strings and lists are
    cut); ``exact_header`` entries (JSON data) are written as they are, for what a
    reader needs back whole.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        root: State | None = None,
        *,
        header: Mapping[str, Any] | None = None,
        exact_header: Mapping[str, Any] | None = None,
        append: bool = False,
        flush_interval: float = 0.005,
        max_interval: float = 0.02,
    ) -> None:
        self.path = Path(path)
        if append:
            drop_torn_line(self.path)
        # Unbuffered: a batch is one system call, and on disk (for the OS) when it returns.
        file = self.path.open("ab" if append else "wb", buffering=0)
        self._root = root
        # The last record of each kind written by write_state (changes are against it).
        self._states: dict[str, tuple[Any, int]] = {}
        self._states_lock = threading.Lock()
        # Paths of the structure in force (see JournalWriter.known).
        known: set[str] = set()
        head: dict[str, Any] | None = None
        if not append:
            import smach

            head = {"format": FORMAT, "smach_version": smach.__version__}
            if root is not None:
                tree = snapshot(root)
                known = {node.path for node in tree.walk()}
                head["structure"] = tree.to_dict()
            head.update({k: summarise(v) for k, v in (header or {}).items()})
            # What a reader needs back exactly (a run's options: a resume reads them).
            head.update(exact_header or {})
        self._writer = JournalWriter(
            file,
            f"smach-journal {self.path.name}",
            root,
            known,
            flush_interval,
            max_interval,
        )
        # Closes the file (writing what is queued) if the journal is dropped without
        # close(), and at interpreter exit.
        self._finalizer = weakref.finalize(self, self._writer.close)
        detach = weakref.WeakMethod(self._detach)
        self._writer.on_error = lambda: (method := detach()) is not None and method()
        if head is not None:
            self._write_now({"kind": "header", **head})
        # The listener: one C call per batch of events (a state machine's step) in the
        # emitting thread, and the tracker for single events (it looks for containers
        # that start); captures hold nothing that can change, so the writer reads them
        # later.
        pending = self._writer.pending
        self._tracker = (
            MachineTracker(root, pending.append, written=not append) if root is not None else None
        )
        super().__init__(self._tracker or pending.append, pending.append)
        self._writer.thread.start()
        if root is not None and hasattr(root, "add_listener"):
            root.add_listener(self)

    def _detach(self) -> None:
        if self._root is not None and hasattr(self._root, "remove_listener"):
            self._root.remove_listener(self)

    @property
    def events_written(self) -> int:
        """How many events are in the file so far."""
        return self._writer.events

    @property
    def structures_written(self) -> int:
        """How many ``structure`` records (machines started after the header) were queued."""
        return self._tracker.structures if self._tracker is not None else 0

    @property
    def pending(self) -> int:
        """How many items (events, pairs of events, records) are queued, not written yet."""
        return len(self._writer.pending)

    def write_record(self, kind: str, **fields: Any) -> None:
        """Write a record that is not an event (e.g. a final summary); durable on return."""
        self._write_now({"kind": kind, **{k: summarise(v) for k, v in fields.items()}})

    def write_raw(self, kind: str, **fields: Any) -> None:
        """Write a record exactly as given (it must be JSON data): e.g. checkpoints.

        Like :meth:`write_record`, the record and every event before it are written
        when this returns.
        """
        self._write_now({"kind": kind, **fields})

    def write_state(self, kind: str, **fields: Any) -> None:
        """Write a record that a resume reads back whole (JSON data): e.g. checkpoints.

        Only what changed since the previous record of ``kind`` is written
        (``{"kind": kind, "change": ...}``), except for the first one of this journal
        object and every :data:`FULL_EVERY` th (``{"kind": kind, "whole": ...}``), so
        a record costs what changed, not the size of the state. :func:`read_states`
        gives the records back whole. Durable on return, like :meth:`write_raw`.
        """
        text = ENCODER.encode(fields)
        state = json.loads(text)  # what a reader will see (tuples are lists, ...)
        with self._states_lock:  # concurrent steps: changes are written in their order
            previous = self._states.get(kind)
            if previous is None or previous[1] + 1 >= FULL_EVERY:
                self._states[kind] = (state, 0)
                self._writer.write_now(f'{{"kind": {json.dumps(kind)}, "whole": {text}}}\n')
                return
            self._states[kind] = (state, previous[1] + 1)
            self._write_now({"kind": kind, "change": diff(previous[0], state)})

    def _write_now(self, record: Mapping[str, Any]) -> None:
        # Encoded here: the caller's data may change once we return.
        self._writer.write_now(ENCODER.encode(record) + "\n")

    def flush(self) -> None:
        """Write every event queued so far before returning."""
        self._writer.flush()

    def close(self) -> None:
        """Detach, write everything queued, close the file, stop the writer thread."""
        self._detach()
        self._finalizer()

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def drop_torn_line(path: Path) -> None:
    """Cut a partial last line (the process died mid-write) before appending.

    Used for every append-only file a killed process may leave: journals, study
    results. The file is truncated in place (one system call, then fsync): a crash at
    any moment leaves either the old file or the repaired one, never less.
    """
    try:
        file = path.open("r+b")
    except FileNotFoundError:
        return
    with file:
        end = file.seek(0, os.SEEK_END)
        if end == 0:
            return
        file.seek(end - 1)
        if file.read(1) == b"\n":
            return
        keep = 0
        position = end
        while position > 0:  # backwards, a block at a time, to the last newline
            start = max(0, position - 65536)
            file.seek(start)
            block = file.read(position - start)
            newline = block.rfind(b"\n")
            if newline >= 0:
                keep = start + newline + 1
                break
            position = start
        file.truncate(keep)
        file.flush()
        os.fsync(file.fileno())


def read_states(records: list[dict[str, Any]], kind: str) -> list[dict[str, Any]]:
    """The records of ``kind`` written by :meth:`Journal.write_state`, whole, in order.

    Records written whole by older versions (``write_raw``) are returned as they are.
    A change with no whole record before it (a journal cut at its head) is an error.
    """
    out: list[dict[str, Any]] = []
    state: Any = None
    for record in records:
        if record.get("kind") != kind:
            continue
        if "whole" in record:
            state = record["whole"]
        elif "change" in record:
            if state is None:
                raise ValueError(f"a {kind!r} change with no whole {kind!r} record before it")
            state = patch(state, record["change"])
        else:
            state = {k: v for k, v in record.items() if k != "kind"}
        out.append({"kind": kind, **state})
    return out


def read_journal(path: str | os.PathLike[str]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(header, records) of a journal; a torn last line (crash mid-write) is skipped."""
    header: dict[str, Any] = {}
    records: list[dict[str, Any]] = []
    scenes = SceneText()  # scenes are written as changes: given back whole
    with Path(path).open(encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                if line.endswith("\n"):
                    raise ValueError(f"{path}:{number}: not a JSON line") from None
                break  # the process died while writing this line
            if number == 1 and record.get("kind") == "header":
                header = record
            else:
                records.append(scenes.record(record))
    return header, records
