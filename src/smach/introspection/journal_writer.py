"""The journal's writer: a queue, a file and a thread that moves one to the other.

Producers (the threads that run the machine) append to :attr:`JournalWriter.pending`
with one C call and never wait. The writer thread loops through four named steps:

1. :meth:`~JournalWriter.wait` - sleep for the current interval (short while events
   come in small batches, longer while they come in large ones or not at all);
2. :meth:`~JournalWriter.take` - pop what is queued, in chunks;
3. :meth:`~JournalWriter.format` - turn a chunk into text (``structure`` lines
   first where needed, see :mod:`smach.introspection.journal_lines`);
4. :meth:`~JournalWriter.write` - one system call for the chunk.

:meth:`JournalWriter.flush` runs steps 2-4 in the calling thread (checkpoints,
``close()``); ``lock`` keeps the lines in queue order whoever writes them.
"""

from __future__ import annotations

import collections
import itertools
import os
import threading
from collections.abc import Callable
from typing import IO, Any

from smach.introspection.journal_lines import StructureItem, line_of, lines_of
from smach.introspection.journal_structures import read_tree, resolve
from smach.introspection.scene_changes import SceneChanges
from smach.log import loggers
from smach.state import State

__all__ = ["JournalWriter"]

CHUNK = 4096
"""Items formatted and written at once."""
BIG_BATCH = 64
"""A batch of at least this many events: the machine runs flat out, poll less often."""


class _Pace:
    """How long the writer sleeps: ``flush_interval`` while events trickle in, doubling
    up to ``max_interval`` while they pour in (each wake-up costs the machine a switch
    of the interpreter lock) or while nothing comes (an idle journal costs nothing)."""

    def __init__(self, flush_interval: float, max_interval: float) -> None:
        self.shortest = flush_interval
        self.longest = max(max_interval, flush_interval)
        self.interval = flush_interval

    def idle(self) -> None:
        self.interval = min(self.longest, self.interval * 2)

    def wrote(self, events: int) -> None:
        if events >= BIG_BATCH:
            self.interval = min(self.longest, self.interval * 2)
        else:
            self.interval = self.shortest


class JournalWriter:
    """The file, the queue and the thread of one journal (no reference back to it)."""

    def __init__(
        self,
        file: IO[bytes],
        name: str,
        root: State | None,
        known: set[str],
        flush_interval: float,
        max_interval: float,
    ) -> None:
        self.file: IO[bytes] | None = file
        self.root = root
        self.known = known
        """Paths of the structure in force (what the events written so far refer to)."""
        self.pace = _Pace(flush_interval, max_interval)
        self.pending: collections.deque[Any] = collections.deque()
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.error: BaseException | None = None
        self.on_error: Callable[[], object] | None = None
        self.batches = 0
        self.events = 0  # events written
        self.pid = os.getpid()
        #: Scenes written as what changed since the last one (scene_changes).
        self.scenes = SceneChanges()
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)

    # -- the thread ---------------------------------------------------------------------
    def _run(self) -> None:
        while self.wait():
            if not self.pending:
                self.pace.idle()
                continue
            try:
                self.pace.wrote(self.flush())
            except Exception as exc:
                self._fail(exc)
                return

    def wait(self) -> bool:
        """Step 1: sleep one interval; False when the journal is closed."""
        return not self.stop.wait(self.pace.interval)

    def take(self, count: int) -> list[Any]:
        """Step 2: pop ``count`` queued items (producers may go on appending)."""
        pop = self.pending.popleft
        return list(itertools.starmap(pop, itertools.repeat((), count)))  # in C

    def format(self, batch: list[Any]) -> tuple[bytes, int]:
        """Step 3: the text of ``batch`` and how many events it holds."""
        known = self.known if self.root is not None else None
        text, events = lines_of(
            batch, known, self._unknown_path, self._structure_line, self.scenes.capture
        )
        return text.encode("utf-8"), events

    def write(self, data: bytes) -> None:
        """Step 4: write ``data`` (an unbuffered file: one system call unless partial)."""
        file = self.file
        assert file is not None  # checked under the lock by flush()
        view = memoryview(data)
        while view:
            view = view[file.write(view) or 0 :]

    def flush(self) -> int:
        """Steps 2-4 for everything queued now, in the calling thread; how many events."""
        with self.lock:
            if self.error is not None:
                raise self.error
            if self.file is None:
                self.pending.clear()
                return 0
            count = len(self.pending)
            if count:
                self.batches += 1
            written = 0
            while count:
                n = min(count, CHUNK)
                count -= n
                data, events = self.format(self.take(n))
                self.write(data)
                self.events += events
                written += events
            return written

    # -- structure lines (called by format, in queue order) -----------------------------
    def _structure_line(self, item: StructureItem) -> str:
        # In place: format() handed this very set to lines_of.
        prefix = item.path + "/"
        self.known.difference_update([p for p in self.known if p.startswith(prefix)])
        self.known.update(node.path for node in item.node.walk())
        return line_of(item.record())

    def _unknown_path(self, path: str) -> str | None:
        """A path no structure mentions (a container that does not report a child):
        the tree of its nearest container read now, once."""
        line = None
        parent = path
        while self.root is not None and "/" in parent.strip("/"):
            parent = parent.rsplit("/", 1)[0]
            state = resolve(self.root, parent)
            if state is not None:
                tree = read_tree(state)
                if tree is not None:
                    line = self._structure_line(StructureItem(parent, None, tree))
                break
        self.known.add(path)  # asked once, whatever the answer
        return line

    # -- life ---------------------------------------------------------------------------
    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        self.pending.clear()
        loggers.logerr(f"journal: writing failed: {exc!r}; it was detached")
        if self.on_error is not None:
            self.on_error()

    def write_now(self, line: str) -> None:
        """Queue ``line`` after everything queued, then write all of it."""
        if self.error is not None:
            raise self.error
        self.pending.append(line)
        self.flush()

    def close(self) -> None:
        if self.pid != os.getpid():
            return  # a forked child: the parent writes its own lines
        try:
            if self.file is not None and self.error is None:
                self.flush()
        finally:
            with self.lock:
                file, self.file = self.file, None
                if file is not None:
                    file.close()
            self.stop.set()
            if self.thread.is_alive() and self.thread is not threading.current_thread():
                self.thread.join(timeout=5)
