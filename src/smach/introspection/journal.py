"""The journal: every event of a run as JSON lines, flushed per event.

The first line is a header (format version, structure snapshot, library version,
and whatever the caller adds, e.g. the seed), so a run can be replayed. Each later
line is one event. Values (userdata) are written as bounded, safe summaries: never
pickled, ``repr`` truncated, containers cut to a few items.
"""

from __future__ import annotations

import json
import math
import os
import threading
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import IO, Any

from smach.introspection.events import Event
from smach.introspection.structure import snapshot
from smach.state import State

__all__ = ["FORMAT", "Journal", "event_record", "read_journal", "summarise"]

FORMAT = "smach-journal/1"
MAX_REPR = 200
MAX_ITEMS = 20
MAX_DEPTH = 3


def summarise(value: Any, depth: int = 0) -> Any:
    """A JSON-safe, size-bounded picture of ``value`` (never its pickle)."""
    if value is None or isinstance(value, bool | int | float):
        if isinstance(value, float) and not math.isfinite(value):  # JSON has no NaN/inf
            return repr(value)
        return value
    if isinstance(value, str):
        return value if len(value) <= MAX_REPR else value[:MAX_REPR] + "…"
    if depth >= MAX_DEPTH:
        return _short_repr(value)
    if isinstance(value, Mapping):
        items = list(value.items())
        out = {str(k): summarise(v, depth + 1) for k, v in items[:MAX_ITEMS]}
        if len(items) > MAX_ITEMS:
            out["…"] = f"{len(items) - MAX_ITEMS} more"
        return out
    if isinstance(value, list | tuple | set | frozenset):
        seq = list(value)
        out_list = [summarise(v, depth + 1) for v in seq[:MAX_ITEMS]]
        if len(seq) > MAX_ITEMS:
            out_list.append(f"… {len(seq) - MAX_ITEMS} more")
        return out_list
    return _short_repr(value)


_PLAIN = (str, int, float, bool, type(None))
_FIELDS: dict[type[Event], tuple[str, ...]] = {}


def event_record(event: Event) -> dict[str, Any]:
    """The journal record of ``event``: ``{"kind": ..., field: summary, ...}``.

    The same as summarising every value of ``event.to_dict()``, without its per-call
    reflection (field names are cached per event class), because journals and viewers
    call it for every event.
    """
    cls = type(event)
    names = _FIELDS.get(cls)
    if names is None:
        names = _FIELDS[cls] = tuple(f.name for f in fields(cls))
    record: dict[str, Any] = {"kind": event.kind}
    for name in names:
        value = getattr(event, name)
        if type(value) in _PLAIN and not (type(value) is float and not math.isfinite(value)):
            record[name] = (
                value
                if type(value) is not str or len(value) <= MAX_REPR
                else value[:MAX_REPR] + "…"
            )
        else:
            record[name] = summarise(value)
    return record


def _short_repr(value: Any) -> str:
    try:
        text = repr(value)
    except Exception as exc:  # a broken __repr__ must not break the journal
        text = f"<{type(value).__name__}: repr failed: {type(exc).__name__}>"
    return text if len(text) <= MAX_REPR else text[:MAX_REPR] + "…"


class Journal:
    """A listener writing JSON lines; use as ``with Journal(path, root): root.execute()``."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        root: State | None = None,
        *,
        header: Mapping[str, Any] | None = None,
        append: bool = False,
    ) -> None:
        self.path = Path(path)
        self._lock = threading.Lock()
        if append:
            drop_torn_line(self.path)
        self._file: IO[str] | None = self.path.open("a" if append else "w", encoding="utf-8")
        self.events_written = 0
        self._root = root
        # Paths the structure written so far knows: an event about any other path (an
        # executive compiled a new plan, a container grew) makes the journal write a
        # fresh ``structure`` record first, so a replay can draw what ran.
        self._known: set[str] = set()
        if not append:
            import smach

            head: dict[str, Any] = {"format": FORMAT, "smach_version": smach.__version__}
            if root is not None:
                tree = snapshot(root)
                self._known = {node.path for node in tree.walk()}
                head["structure"] = tree.to_dict()
            head.update({k: summarise(v) for k, v in (header or {}).items()})
            self._write({"kind": "header", **head})
        if root is not None and hasattr(root, "add_listener"):
            root.add_listener(self)

    def __call__(self, event: Event) -> None:
        self.write_event(event)

    def write_event(self, event: Event) -> None:
        if self._root is not None and event.path not in self._known:
            self._write_structure(event.path)
        self._write(event_record(event))
        self.events_written += 1

    def _write_structure(self, path: str) -> None:
        assert self._root is not None
        tree = snapshot(self._root)
        self._known = {node.path for node in tree.walk()}
        # A path the tree does not report (a user container without get_children) is
        # remembered anyway, so it costs one snapshot and not one per event.
        self._known.add(path)
        self._write({"kind": "structure", "structure": tree.to_dict()})

    def write_record(self, kind: str, **fields: Any) -> None:
        """Write a record that is not an event (e.g. a final summary)."""
        self._write({"kind": kind, **{k: summarise(v) for k, v in fields.items()}})

    def write_raw(self, kind: str, **fields: Any) -> None:
        """Write a record exactly as given (it must be JSON data): e.g. checkpoints."""
        self._write({"kind": kind, **fields})

    def _write(self, record: Mapping[str, Any]) -> None:
        line = json.dumps(record, ensure_ascii=False, default=_short_repr)
        with self._lock:
            if self._file is None:
                return
            self._file.write(line + "\n")
            self._file.flush()

    def close(self) -> None:
        if self._root is not None and hasattr(self._root, "remove_listener"):
            self._root.remove_listener(self)
        with self._lock:
            if self._file is not None:
                self._file.close()
                self._file = None

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def drop_torn_line(path: Path) -> None:
    """Cut a partial last line (the process died mid-write) before appending.

    Used for every append-only file a killed process may leave: journals, study
    results.
    """
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        path.write_bytes(data[: data.rfind(b"\n") + 1])


def read_journal(path: str | os.PathLike[str]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(header, records) of a journal; a torn last line (crash mid-write) is skipped."""
    header: dict[str, Any] = {}
    records: list[dict[str, Any]] = []
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
                records.append(record)
    return header, records
