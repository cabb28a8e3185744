"""Where a viewer's records come from: a live tree, a journal, or (later) ROS topics.

A :class:`Source` hands the viewer *records*, the dictionaries of the journal
format (see :mod:`smach.introspection.journal` and :mod:`smach.introspection.model`).
The viewer's serving thread calls :meth:`Source.poll` every tenth of a second or so;
nothing else is asked of a source. To follow another kind of executive (a remote
one through the ROS 2 IntrospectionServer topics, say), write a class with these four
members that turns its messages into records, and pass it to
:func:`smach.introspection.serve`.

:class:`LiveSource` watches a tree in this process. Its listener is a
:class:`~smach.introspection.events.CaptureListener` whose functions are the bound
``append`` and ``extend`` of a bounded deque: the executing threads pay one C call
per event (no event object is built for it) and never wait for the viewer.
Everything else (building records and JSON, noticing structure changes) happens in
the viewer's thread; a userdata value that could change is summarised into the
capture when it is written, so the viewer shows it as written. When the viewer
falls behind the deque
drops the oldest events; the next poll then reads the active states from the live
tree (a ``resync`` record) so the picture is right again. The pump also folds at
most ``max_rate`` events a second on average (``burst`` at once after a quiet
spell): a machine that produces more has the older events of each poll skipped and
resynced the same way, so what a viewer costs a fast machine is bounded, whatever
its event rate, while a short run is shown event by event.
"""

from __future__ import annotations

import collections
import itertools
import json
import os
import time
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from smach.introspection.events import Capture, CaptureListener
from smach.introspection.journal import capture_record, summarise
from smach.introspection.journal_lines import StructureItem
from smach.introspection.journal_structures import MachineTracker
from smach.introspection.scene_changes import SceneText
from smach.introspection.structure import snapshot
from smach.state import State

__all__ = ["JournalSource", "LiveSource", "Source"]


@runtime_checkable
class Source(Protocol):
    """What the viewer reads; see the module documentation."""

    @property
    def live(self) -> bool:
        """True while more records may come (a running tree, a followed journal)."""
        ...

    def header(self) -> dict[str, Any]:
        """The journal header: at least ``structure`` (a StateNode dict) when known."""
        ...

    def poll(self) -> list[dict[str, Any]]:
        """The records that arrived since the last call (never blocks)."""
        ...

    def close(self) -> None: ...


def _walk_containers(state: State) -> list[tuple[str, Any]]:
    from smach.container import Container

    found: list[tuple[str, Any]] = []
    stack: list[State] = [state]
    while stack:
        s = stack.pop()
        if isinstance(s, Container):
            found.append((s.path or "/ROOT", s))
            stack.extend(s.get_children().values())
    return found


class LiveSource:
    """Records of a tree running in this process (attach before or during a run)."""

    live = True

    def __init__(
        self,
        root: State,
        *,
        buffer: int = 4096,
        max_rate: float = 1000.0,
        burst: int = 256,
        userdata_every: float = 1.0,
        title: str | None = None,
    ) -> None:
        from smach.container import Container

        if not isinstance(root, Container):
            raise TypeError(
                f"the viewer needs a container (StateMachine, Concurrence, ...), got "
                f"{type(root).__name__}"
            )
        self.root = root
        self.title = title or f"{type(root).__name__} {root.path or '/ROOT'}"
        self.userdata_every = userdata_every
        self.max_rate = max_rate
        self.burst = burst
        self._allowance = float(burst)
        self._last_poll = time.monotonic()
        self._pending: collections.deque[Capture] = collections.deque(maxlen=buffer)
        # Single events go through the tracker: a container that starts for the first
        # time (a new plan) has its tree queued before its start (see journal_structures).
        self._tracker = MachineTracker(root, self._pending.append, written=True)
        self._listener = CaptureListener(self._tracker, self._pending.extend)
        self._known: set[str] = set()
        self._last_userdata: dict[str, str] = {}
        self._next_userdata = 0.0
        self.dropped_batches = 0
        tree = snapshot(root)
        self._known = {n.path for n in tree.walk()}
        self._header: dict[str, Any] = {
            "kind": "header",
            "format": "smach-journal/1",
            "source": "live",
            "title": self.title,
            "structure": tree.to_dict(),
        }
        root.add_listener(self._listener)

    def header(self) -> dict[str, Any]:
        return self._header

    def poll(self) -> list[dict[str, Any]]:
        pending = self._pending
        overflow = len(pending) >= (pending.maxlen or 0)
        # Take what is there (n x popleft, in C; appends may go on meanwhile).
        count = len(pending)
        captures: list[Any] = list(  # captures and StructureItems
            itertools.starmap(pending.popleft, itertools.repeat((), count))
        )
        records: list[dict[str, Any]] = []
        now = time.monotonic()
        allowance = min(self.burst, self._allowance + (now - self._last_poll) * self.max_rate)
        self._last_poll = now
        skip = count - int(allowance)
        if skip > 0:
            # Coalesce: a page shows a few hundred records per update; folding every
            # event of a fast machine would cost the machine more than it shows. Keep
            # the newest ones, then resync (which also notices a changed structure).
            overflow = True
            captures = captures[skip:]
        self._allowance = max(0.0, allowance - len(captures))
        known = self._known
        for capture in captures:
            if type(capture) is StructureItem:
                records.append(capture.record())
                prefix = capture.path + "/"
                known.difference_update([p for p in known if p.startswith(prefix)])
                known.update(node.path for node in capture.node.walk())
                continue
            path = capture[1]
            if path not in known:
                records.append(self._structure_record(path))
                known = self._known
            try:
                records.append(capture_record(capture))
            except Exception as exc:  # a value whose summary fails must not stop the viewer
                records.append({"kind": "error", "path": path, "time": capture[2],
                                "error_type": "ViewerError", "message": repr(exc)})  # fmt: skip
        if overflow:
            self.dropped_batches += 1
            active = self.active_paths()
            unknown = next((path for path in active if path not in self._known), None)
            if unknown is not None:  # the skipped events were about a changed tree
                records.append(self._structure_record(unknown))
            records.append(
                {
                    "kind": "resync",
                    "path": self.root.path or "/ROOT",
                    "time": time.monotonic(),
                    "active": active,
                    "reason": "the viewer fell behind and skipped events",
                }
            )
        now = time.monotonic()
        if now >= self._next_userdata:
            self._next_userdata = now + self.userdata_every
            records.extend(self._userdata_records(now))
        return records

    def active_paths(self) -> list[str]:
        """The active states read from the live tree (all branches)."""
        from smach.container import Container

        found: list[str] = []
        if not self.root.is_running():
            return found
        stack: list[tuple[str, State]] = [(self.root.path or "/ROOT", self.root)]
        while stack:
            path, state = stack.pop()
            found.append(path)
            if isinstance(state, Container):
                children = state.get_children()
                for label in list(state.get_active_states()):
                    child = children.get(label)
                    if child is not None:
                        stack.append((f"{path}/{label}", child))
        return found

    def _structure_record(self, path: str) -> dict[str, Any]:
        tree = snapshot(self.root)
        self._known = {n.path for n in tree.walk()}
        self._known.add(path)
        return {"kind": "structure", "time": time.monotonic(), "structure": tree.to_dict()}

    def _userdata_records(self, now: float) -> list[dict[str, Any]]:
        records = []
        for path, container in _walk_containers(self.root):
            try:
                data = dict(container.userdata._data)
                values = {str(k): summarise(v) for k, v in data.items()}
                text = json.dumps(values, sort_keys=True, default=str)
            except Exception:  # changed while we read it: next time
                continue
            if self._last_userdata.get(path) != text:
                self._last_userdata[path] = text
                records.append({"kind": "userdata", "path": path, "time": now, "values": values})
        return records

    def close(self) -> None:
        self.root.remove_listener(self._listener)


class JournalSource:
    """Records of a journal file; with ``follow=True``, also the lines appended later."""

    def __init__(self, path: str | os.PathLike[str], *, follow: bool = False) -> None:
        self.path = Path(path)
        self.follow = follow
        self._file = self.path.open(encoding="utf-8")
        self._partial = ""
        self._header: dict[str, Any] = {}
        self._buffered: list[dict[str, Any]] = []
        self._line = 0
        self._scenes = SceneText()  # scenes are written as changes: given back whole
        first = self._read()
        if first and first[0].get("kind") == "header":
            self._header = first.pop(0)
        self._buffered = first
        if not self._header:
            self._header = {"kind": "header", "format": "unknown"}
        self.title = str(self._header.get("title") or self.path.name)

    @property
    def live(self) -> bool:
        return self.follow

    def header(self) -> dict[str, Any]:
        return self._header

    def _read(self) -> list[dict[str, Any]]:
        records: list[dict[str, Any]] = []
        chunk = self._file.read()
        if not chunk:
            return records
        text = self._partial + chunk
        lines = text.split("\n")
        self._partial = lines.pop()  # "" after a complete last line
        for line in lines:
            self._line += 1
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{self.path}:{self._line}: not a JSON line ({exc})") from None
            if isinstance(record, dict):
                records.append(self._scenes.record(record))
        return records

    def poll(self) -> list[dict[str, Any]]:
        records, self._buffered = self._buffered, []
        if self.follow:
            records.extend(self._read())
        return records

    def close(self) -> None:
        self._file.close()
