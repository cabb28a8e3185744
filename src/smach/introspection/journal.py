"""The journal: every event of a run as JSON lines, written by a background thread.

The first line is a header (format version, structure snapshot, library version,
and whatever the caller adds, e.g. the seed), so a run can be replayed. Each later
line is one event. Values (userdata) are written as bounded, safe summaries: never
pickled, ``repr`` truncated, containers cut to a few items.

What the executing thread pays: the journal is a
:class:`~smach.introspection.events.CaptureListener` whose functions are the
``append`` of a queue, so an event (or a state machine's exited + transition pair)
costs the thread that emits it one C call on a tuple (values that may still change, such as a userdata list, are
summarised into the capture when the event happens, so the record shows the value as
it was). A writer thread wakes every few milliseconds, formats the queued events as
JSON lines, notices new paths (it then writes a ``structure`` record first, so a
replay can draw what ran) and writes each batch with one system call.

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

Structure records are written by the writer when it meets a new path, from a
snapshot taken then: if the tree changed again within those milliseconds (a plan
replaced twice), the snapshot shows the newer tree.
"""

from __future__ import annotations

import collections
import itertools
import json
import math
import os
import threading
import weakref
from collections.abc import Callable, Mapping
from json.encoder import c_make_encoder, encode_basestring  # type: ignore[attr-defined]
from pathlib import Path
from typing import IO, Any

from smach.introspection.events import (
    Capture,
    CaptureListener,
    ContainerStarted,
    ContainerTerminated,
    Event,
    StateEntered,
    StateExited,
    Transition,
    field_names,
)
from smach.introspection.structure import snapshot
from smach.introspection.summary import (
    MAX_DEPTH,
    MAX_ITEMS,
    MAX_REPR,
    PLAIN,
    Summary,
    short_repr,
    summarise,
)
from smach.state import State

__all__ = [
    "FORMAT",
    "MAX_DEPTH",
    "MAX_ITEMS",
    "MAX_REPR",
    "Journal",
    "capture_record",
    "event_record",
    "read_journal",
    "summarise",
]

FORMAT = "smach-journal/1"
_short_repr = short_repr


def _plain(*texts: object) -> bool:
    """Whether these are strings that a record keeps unchanged (none is cut to MAX_REPR)."""
    total = 0
    for text in texts:
        if type(text) is not str:
            return False
        total += len(text)
    return total <= MAX_REPR


def capture_record(capture: Capture) -> dict[str, Any]:
    """The journal record of a capture: ``{"kind": ..., field: summary, ...}``.

    The same as summarising every value of the event's ``to_dict()`` (a
    :class:`~smach.introspection.summary.Summary` gives its value), without its
    per-call reflection, because journals and viewers call it for every event.
    """
    cls = capture[0]
    fast = _RECORDS.get(cls)
    if fast is not None:
        t = capture[2]
        if type(t) is float and t - t == 0.0 and _plain(capture[1], *capture[3:]):
            return fast(*capture[1:])  # plain short strings: nothing to summarise
    record: dict[str, Any] = {"kind": cls.kind}
    for name, value in zip(field_names(cls), capture[1:], strict=False):
        kind = type(value)
        if kind is str:
            record[name] = value if len(value) <= MAX_REPR else value[:MAX_REPR] + "…"
        elif kind is Summary:
            record[name] = value.value
        elif kind in PLAIN and not (kind is float and not math.isfinite(value)):
            record[name] = value
        else:
            record[name] = summarise(value)
    return record


def _entered_record(path: str, t: float, thread: str, label: str) -> dict[str, Any]:
    return {"kind": "state_entered", "path": path, "time": t, "thread": thread, "label": label}


def _exited_record(
    path: str, t: float, thread: str, label: str, outcome: str | None
) -> dict[str, Any]:
    return {
        "kind": "state_exited",
        "path": path,
        "time": t,
        "thread": thread,
        "label": label,
        "outcome": outcome,
    }


def _transition_record(
    path: str, t: float, thread: str, source: str, outcome: str, target: str
) -> dict[str, Any]:
    return {
        "kind": "transition",
        "path": path,
        "time": t,
        "thread": thread,
        "source": source,
        "outcome": outcome,
        "target": target,
    }


_RECORDS: dict[type[Event], Callable[..., dict[str, Any]]] = {
    StateEntered: _entered_record,
    StateExited: _exited_record,
    Transition: _transition_record,
}


def event_record(event: Event) -> dict[str, Any]:
    """The journal record of ``event`` (see :func:`capture_record`)."""
    return capture_record(event.capture())


_ENCODER = json.JSONEncoder(ensure_ascii=False, default=short_repr)


def _encode(value: Any) -> str:
    """JSON text of acyclic data: summaries and records built from them."""
    return "".join(_C_ENCODE(value, 0)) if _C_ENCODE is not None else _ENCODER.encode(value)


_C_ENCODE = (
    c_make_encoder(None, short_repr, encode_basestring, None, ": ", ", ", False, False, True)
    if c_make_encoder is not None
    else None
)
_KEYS: dict[type[Event], tuple[str, ...]] = {}


def _capture_line(capture: Capture) -> str:
    """The JSON line of any capture: the text of its :func:`capture_record`, the time
    written to the nanosecond (9 decimals), without building the record."""
    cls = capture[0]
    keys = _KEYS.get(cls)
    if keys is None:
        names = field_names(cls)
        keys = _KEYS[cls] = (
            f'{{"kind": {encode_basestring(cls.kind)}, {encode_basestring(names[0])}: ',
            *(f", {encode_basestring(name)}: " for name in names[1:]),
        )
    parts: list[str] = []
    put = parts.append
    for key, value in zip(keys, capture[1:], strict=True):
        put(key)
        kind = type(value)
        if kind is str:
            put(encode_basestring(value if len(value) <= MAX_REPR else value[:MAX_REPR] + "…"))
        elif kind is float:
            if not math.isfinite(value):
                put(encode_basestring(repr(value)))
            elif key is keys[1]:  # the time
                put(f"{value:.9f}")
            else:
                put(float.__repr__(value))
        elif value is None:
            put("null")
        elif kind is bool:
            put("true" if value else "false")
        elif kind is int:
            put(int.__repr__(value))
        elif kind is Summary:
            put(_encode(value.value))
        else:
            put(_encode(summarise(value)))
    put("}\n")
    return "".join(parts)


def _line(item: Any) -> str:
    """The JSON line (with its newline) of a queued item: a capture, a record or a line."""
    try:
        if type(item) is str:
            return item
        if type(item) is tuple:
            return _capture_line(item)
        return _encode(item) + "\n"
    except Exception as exc:  # one bad value must not cost the other lines
        return (
            _ENCODER.encode(
                {"kind": "error", "error_type": "JournalError", "message": short_repr(exc)}
            )
            + "\n"
        )


# The lines of the three events of every transition are cached per state, split
# around the time: only the time differs from one run of a state to the next. An
# entry is used when every string matches; a cache grown past _CACHE_LIMIT entries is
# emptied (a tree with that many states, or names that change all the time).
_ENTERED: dict[str, tuple[str, str, str, str]] = {}
_EXITED: dict[str, tuple[str, str, str | None, str, str]] = {}
_TRANSITIONS: dict[str, dict[str, tuple[str, str, str, str, str]]] = {}
_PAIRS: dict[str, tuple[str, str, str, str, str, str, str, str]] = {}
_CONTAINERS: dict[tuple[type[Event], str], tuple[tuple[Any, ...], str, str]] = {}
_CACHE_LIMIT = 20_000
_TIMED = "%s%.9f%s"
_PAIR = "%s%.9f%s%.9f%s"
_STEP = "%s%.9f%s%.9f%s%s%.9f%s"


def _entered_parts(path: str, thread: str, label: str) -> tuple[str, str, str, str] | None:
    if not _plain(path, thread, label):
        return None
    q = encode_basestring
    if len(_ENTERED) > _CACHE_LIMIT:
        _ENTERED.clear()
    entry = _ENTERED[path] = (
        thread,
        label,
        f'{{"kind": "state_entered", "path": {q(path)}, "time": ',
        f', "thread": {q(thread)}, "label": {q(label)}}}\n',
    )
    return entry


def _exited_parts(
    path: str, thread: str, label: str, outcome: str | None
) -> tuple[str, str, str | None, str, str] | None:
    if not _plain(path, thread, label, "" if outcome is None else outcome):
        return None
    q = encode_basestring
    if len(_EXITED) > _CACHE_LIMIT:
        _EXITED.clear()
    entry = _EXITED[path] = (
        thread,
        label,
        outcome,
        f'{{"kind": "state_exited", "path": {q(path)}, "time": ',
        f', "thread": {q(thread)}, "label": {q(label)}, '
        f'"outcome": {"null" if outcome is None else q(outcome)}}}\n',
    )
    return entry


def _transition_parts(
    path: str, thread: str, source: str, outcome: str, target: str
) -> tuple[str, str, str, str, str] | None:
    if not _plain(path, thread, source, outcome, target):
        return None
    q = encode_basestring
    if len(_TRANSITIONS) > _CACHE_LIMIT:
        _TRANSITIONS.clear()
    of_container = _TRANSITIONS.setdefault(path, {})
    if len(of_container) > _CACHE_LIMIT:
        of_container.clear()
    entry = of_container[source] = (
        thread,
        outcome,
        target,
        f'{{"kind": "transition", "path": {q(path)}, "time": ',
        f', "thread": {q(thread)}, "source": {q(source)}, "outcome": {q(outcome)}, '
        f'"target": {q(target)}}}\n',
    )
    return entry


def _container_parts(capture: Capture) -> tuple[tuple[Any, ...], str, str]:
    """The line of a container_started / container_terminated split around its time."""
    line = _capture_line((capture[0], capture[1], 0.0, *capture[3:]))
    head, found, tail = line.partition('"time": 0.000000000')
    if not found:
        raise ValueError("no time in the line")  # not expected: the general path then
    if len(_CONTAINERS) > _CACHE_LIMIT:
        _CONTAINERS.clear()
    entry = _CONTAINERS[capture[0], capture[1]] = (capture[3:], head + '"time": ', tail)
    return entry


def _pair_parts(
    path: str, thread: str, label: str, outcome: str, container: str, target: str
) -> tuple[str, str, str, str, str, str, str, str] | None:
    """The parts of a state_exited line and of the transition line that follows it."""
    exited = _exited_parts(path, thread, label, outcome)
    moved = _transition_parts(container, thread, label, outcome, target)
    if exited is None or moved is None:
        return None
    if len(_PAIRS) > _CACHE_LIMIT:
        _PAIRS.clear()
    entry = _PAIRS[path] = (
        thread,
        label,
        outcome,
        container,
        target,
        exited[3],
        exited[4] + moved[3],
        moved[4],
    )
    return entry


def _lines(
    items: list[Any], known: set[str] | None, new_path: Callable[[str], str | None]
) -> tuple[str, int]:
    """The JSON lines of queued items, in order, and how many of them are events.

    ``new_path(path)`` is asked for every event about a path not in ``known`` (it
    returns a ``structure`` line to write first, or None); ``known`` None: nobody asks.

    The three events of every transition are written from cached parts (see
    _ENTERED), their times formatted in one C call for the whole batch: several times
    cheaper than building and encoding a record. Such a line is the one :func:`_line`
    writes. Any other item, or any surprise (a value that is not a short string, a
    time that is not a finite float), takes :func:`_line`.
    """
    template: list[str] = []
    args: list[Any] = []
    timed = template.append
    arg = args.append
    entered_of = _ENTERED.get
    exited_of = _EXITED.get
    pairs_of = _PAIRS.get
    transitions_of = _TRANSITIONS.get
    containers_of = _CONTAINERS.get
    others = 0
    for item in items:
        if type(item) is not tuple:
            others += 1  # a record or a line, not an event
            timed("%s")
            arg(_line(item))
            continue
        if type(item[0]) is tuple:  # captures that came together (capture_many)
            try:
                # A state machine's step: state_exited + transition (+ state_entered of
                # the next state), all from one thread, the first two at one time.
                exited = item[0]
                moved = item[1]
                _, path, t, thread, label, outcome = exited
                if (
                    exited[0] is StateExited
                    and moved[0] is Transition
                    and type(t) is float
                    and t - t == 0.0
                    and moved[2] is t
                    and moved[3] is thread
                    and moved[4] == label
                    and moved[5] == outcome
                    and (known is None or (path in known and moved[1] in known))
                ):
                    container, target = moved[1], moved[6]
                    pair = pairs_of(path)
                    if (
                        pair is None
                        or pair[0] != thread
                        or pair[1] != label
                        or pair[2] != outcome
                        or pair[3] != container
                        or pair[4] != target
                    ):
                        pair = _pair_parts(path, thread, label, outcome, container, target)
                    if pair is not None:
                        if len(item) == 2:
                            timed(_PAIR)
                            arg(pair[5])
                            arg(t)
                            arg(pair[6])
                            arg(t)
                            arg(pair[7])
                            others -= 1  # two events in one item
                            continue
                        _, _, entered = item  # three: the next state's state_entered
                        _, next_path, t_next, next_thread, next_label = entered
                        if (
                            entered[0] is StateEntered
                            and next_thread is thread
                            and next_label == target
                            and type(t_next) is float
                            and t_next - t_next == 0.0
                            and (known is None or next_path in known)
                        ):
                            e = entered_of(next_path)
                            if e is None or e[0] != thread or e[1] != next_label:
                                e = _entered_parts(next_path, thread, next_label)
                            if e is not None:
                                timed(_STEP)
                                arg(pair[5])
                                arg(t)
                                arg(pair[6])
                                arg(t)
                                arg(pair[7])
                                arg(e[2])
                                arg(t_next)
                                arg(e[3])
                                others -= 2  # three events in one item
                                continue
            except Exception:  # not the usual step: one by one below
                pass
            text, events = _lines(list(item), known, new_path)
            others -= events - 1
            timed("%s")
            arg(text)
            continue
        if known is not None and item[1] not in known:
            structure = new_path(item[1])
            if structure is not None:
                timed("%s")
                arg(structure)
        try:
            cls = item[0]
            t = item[2]
            if type(t) is float and t - t == 0.0:
                if cls is ContainerStarted or cls is ContainerTerminated:
                    rest = item[3:]
                    c = containers_of((cls, item[1]))
                    if c is None or c[0] != rest:
                        c = _container_parts(item)
                    timed(_TIMED)
                    arg(c[1])
                    arg(t)
                    arg(c[2])
                    continue
                if cls is StateEntered:
                    _, path, _, thread, label = item
                    e = entered_of(path)
                    if e is None or e[0] != thread or e[1] != label:
                        e = _entered_parts(path, thread, label)
                    if e is not None:
                        timed(_TIMED)
                        arg(e[2])
                        arg(t)
                        arg(e[3])
                        continue
                elif cls is StateExited:
                    _, path, _, thread, label, outcome = item
                    x = exited_of(path)
                    if x is None or x[0] != thread or x[1] != label or x[2] != outcome:
                        x = _exited_parts(path, thread, label, outcome)
                    if x is not None:
                        timed(_TIMED)
                        arg(x[3])
                        arg(t)
                        arg(x[4])
                        continue
                elif cls is Transition:
                    _, path, _, thread, source, outcome, target = item
                    of_container = transitions_of(path)
                    m = None if of_container is None else of_container.get(source)
                    if m is None or m[0] != thread or m[1] != outcome or m[2] != target:
                        m = _transition_parts(path, thread, source, outcome, target)
                    if m is not None:
                        timed(_TIMED)
                        arg(m[3])
                        arg(t)
                        arg(m[4])
                        continue
        except Exception:  # not plain strings: the general path below
            pass
        timed("%s")
        arg(_line(item))
    return "".join(template) % tuple(args), len(items) - others


_CHUNK = 4096
_BIG_BATCH = 64


class _Writer:
    """The file, the queue and the thread of one journal (no reference back to it).

    Producers append to ``pending`` (any thread; a C call, never blocks). The thread
    wakes every ``flush_interval`` to ``max_interval`` seconds and writes what is
    queued; :meth:`flush` does the same at once in the calling thread. ``lock`` is
    held while items are taken from the queue and written, so lines reach the file
    in queue order whoever writes them.
    """

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
        self.flush_interval = flush_interval
        self.max_interval = max(max_interval, flush_interval)
        self.pending: collections.deque[Any] = collections.deque()
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.error: BaseException | None = None
        self.on_error: Callable[[], object] | None = None
        self.batches = 0
        self.events = 0  # events written
        self.pid = os.getpid()
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        interval = self.flush_interval
        while not self.stop.wait(interval):
            if not self.pending:
                # Nothing came: poll less often (an idle journal costs next to nothing).
                interval = min(self.max_interval, interval * 2)
                continue
            try:
                written = self.flush()
            except Exception as exc:
                self._fail(exc)
                return
            # A machine running flat out: gather longer batches (each costs it a switch
            # of the interpreter lock), up to max_interval; small batches: poll often.
            if written >= _BIG_BATCH:
                interval = min(self.max_interval, interval * 2)
            else:
                interval = self.flush_interval

    def _fail(self, exc: BaseException) -> None:
        self.error = exc
        self.pending.clear()
        import smach

        smach.logerr(f"journal: writing failed: {exc!r}; it was detached")
        if self.on_error is not None:
            self.on_error()

    def _new_path(self, path: str) -> str | None:
        """The structure line to write before the first event about ``path``."""
        if path in self.known or self.root is None:
            return None
        for _ in range(3):
            try:
                tree = snapshot(self.root)
                break
            except RuntimeError:  # the tree changed while we read it: read it again
                continue
        else:
            self.known.add(path)
            return None
        self.known = {node.path for node in tree.walk()}
        # A path the tree does not report (a user container without get_children) is
        # remembered anyway, so it costs one snapshot and not one per event.
        self.known.add(path)
        return _line({"kind": "structure", "structure": tree.to_dict()})

    def flush(self) -> int:
        """Write every queued item now (in the calling thread); return how many events."""
        with self.lock:
            if self.error is not None:
                raise self.error
            file = self.file
            if file is None:
                self.pending.clear()
                return 0
            pending = self.pending
            pop = pending.popleft
            no_args = ()
            taken = count = len(pending)  # producers may keep adding: take what is there
            written = 0
            while count:
                n = min(count, _CHUNK)
                count -= n
                known = self.known if self.root is not None else None
                # n x pending.popleft(), in C.
                batch = list(itertools.starmap(pop, itertools.repeat(no_args, n)))
                text, events = _lines(batch, known, self._new_path)
                self.events += events
                written += events
                data = memoryview(text.encode("utf-8"))
                while data:  # an unbuffered file: one system call, unless it is partial
                    data = data[file.write(data) or 0 :]
            if taken:
                self.batches += 1
            return written

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


class Journal(CaptureListener):
    """A listener writing JSON lines; use as ``with Journal(path, root): root.execute()``.

    ``flush_interval`` and ``max_interval`` (seconds) bound how often the writer
    thread looks for queued events: see the module documentation for the durability
    contract. Attach it to a tree by passing ``root``, or with ``add_listener``.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        root: State | None = None,
        *,
        header: Mapping[str, Any] | None = None,
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
        # Paths the structure written so far knows: an event about any other path (an
        # executive compiled a new plan, a container grew) makes the writer write a
        # fresh ``structure`` record first, so a replay can draw what ran.
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
        self._writer = _Writer(
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
        # The listener: one C call per event (or per pair of events) in the emitting
        # thread; captures hold nothing that can change, so the writer reads them later.
        pending = self._writer.pending
        super().__init__(pending.append, pending.append)
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
    def pending(self) -> int:
        """How many items (events, pairs of events, records) are queued, not written yet."""
        return len(self._writer.pending)

    def write_event(self, event: Event) -> None:
        """Queue ``event`` (the listener does this for every event of the tree)."""
        self._writer.pending.append(event.capture())

    def write_record(self, kind: str, **fields: Any) -> None:
        """Write a record that is not an event (e.g. a final summary); durable on return."""
        self._write_now({"kind": kind, **{k: summarise(v) for k, v in fields.items()}})

    def write_raw(self, kind: str, **fields: Any) -> None:
        """Write a record exactly as given (it must be JSON data): e.g. checkpoints.

        Like :meth:`write_record`, the record and every event before it are written
        when this returns.
        """
        self._write_now({"kind": kind, **fields})

    def _write_now(self, record: Mapping[str, Any]) -> None:
        # Encoded here: the caller's data may change once we return.
        self._writer.write_now(_ENCODER.encode(record) + "\n")

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
