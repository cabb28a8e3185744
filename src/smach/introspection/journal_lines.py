"""The JSON lines of a journal: records of events, and their text, fast.

A journal writes millions of lines: the three events of every state machine step
(``state_exited``, ``transition``, ``state_entered``) are written from text cached
per state and split around the time, so that a step costs a ``%`` format and not a
record built and encoded (see :func:`lines_of`). Every other item takes the general
path, :func:`line_of`, which writes the text of :func:`capture_record`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from json.encoder import c_make_encoder, encode_basestring  # type: ignore[attr-defined]
from typing import Any

from smach.introspection.events import (
    Capture,
    ContainerStarted,
    ContainerTerminated,
    Event,
    StateEntered,
    StateExited,
    Transition,
    field_names,
)
from smach.introspection.summary import MAX_REPR, PLAIN, Summary, short_repr, summarise

__all__ = ["ENCODER", "StructureItem", "capture_record", "event_record", "line_of", "lines_of"]


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


ENCODER = json.JSONEncoder(ensure_ascii=False, default=short_repr)


class StructureItem:
    """A queued ``structure`` record: the tree of the container at ``path`` as it started.

    Built in the thread that started the container (the tree may be replaced a moment
    later: an executive compiles its next plan), turned into text by the writer.
    """

    __slots__ = ("node", "path", "time")

    def __init__(self, path: str, time: float | None, node: Any) -> None:
        self.path = path
        self.time = time
        self.node = node  # a StateNode (immutable)

    def record(self) -> dict[str, Any]:
        from smach.introspection.compact import compact

        record: dict[str, Any] = {"kind": "structure", "path": self.path}
        if self.time is not None:
            record["time"] = self.time
        # Compact: a plan of 2000 steps costs tens of bytes per step (read with
        # compact.structure_of).
        record["compact"] = compact(self.node.to_dict())
        return record


def _encode(value: Any) -> str:
    """JSON text of acyclic data: summaries and records built from them."""
    return "".join(_C_ENCODE(value, 0)) if _C_ENCODE is not None else ENCODER.encode(value)


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


def line_of(item: Any) -> str:
    """The JSON line (with its newline) of a queued item: a capture, a record or a line."""
    try:
        if type(item) is str:
            return item
        if type(item) is tuple:
            return _capture_line(item)
        return _encode(item) + "\n"
    except Exception as exc:  # one bad value must not cost the other lines
        return (
            ENCODER.encode(
                {"kind": "error", "error_type": "JournalError", "message": short_repr(exc)}
            )
            + "\n"
        )


# The lines of the events of states, transitions and containers are cached per path,
# split around the time: only the time differs from one run of a state to the next. An entry is the strings
# it was made of, then the text before and after the time (``entry[-2]``,
# ``entry[-1]``); it is used when every string matches. A cache grown past
# _CACHE_LIMIT entries is emptied (a tree with that many states, or names that change
# all the time). The ``*_parts`` functions give the entry of a capture, made and cached
# if needed, or None when its values are not plain short strings.
_ENTERED: dict[str, tuple[str, str, str, str]] = {}
_EXITED: dict[str, tuple[str, str, str | None, str, str]] = {}
_TRANSITIONS: dict[str, dict[str, tuple[str, str, str, str, str]]] = {}
_Pair = tuple[str, str, str, str, str, str, str, str]
_PAIRS: dict[str, _Pair] = {}
_CONTAINERS: dict[tuple[type[Event], str], tuple[tuple[Any, ...], str, str]] = {}
_CACHE_LIMIT = 20_000
_TIMED = "%s%.9f%s"
_PAIR = "%s%.9f%s%.9f%s"
_STEP = "%s%.9f%s%.9f%s%s%.9f%s"


def _cache_in(cache: dict[Any, Any]) -> dict[Any, Any]:
    """``cache``, emptied first when it has grown past the limit."""
    if len(cache) > _CACHE_LIMIT:
        cache.clear()
    return cache


def _entered_parts(entered: Capture) -> tuple[str, str, str, str] | None:
    _, path, _, thread, label = entered
    entry = _ENTERED.get(path)
    if entry is not None and entry[0] == thread and entry[1] == label:
        return entry
    if not _plain(path, thread, label):
        return None
    q = encode_basestring
    entry = _cache_in(_ENTERED)[path] = (
        thread,
        label,
        f'{{"kind": "state_entered", "path": {q(path)}, "time": ',
        f', "thread": {q(thread)}, "label": {q(label)}}}\n',
    )
    return entry


def _exited_parts(exited: Capture) -> tuple[str, str, str | None, str, str] | None:
    _, path, _, thread, label, outcome = exited
    entry = _EXITED.get(path)
    if entry is not None and entry[0] == thread and entry[1] == label and entry[2] == outcome:
        return entry
    if not _plain(path, thread, label, "" if outcome is None else outcome):
        return None
    q = encode_basestring
    entry = _cache_in(_EXITED)[path] = (
        thread,
        label,
        outcome,
        f'{{"kind": "state_exited", "path": {q(path)}, "time": ',
        f', "thread": {q(thread)}, "label": {q(label)}, '
        f'"outcome": {"null" if outcome is None else q(outcome)}}}\n',
    )
    return entry


def _transition_parts(moved: Capture) -> tuple[str, str, str, str, str] | None:
    _, path, _, thread, source, outcome, target = moved
    of_container = _TRANSITIONS.get(path)
    entry = None if of_container is None else of_container.get(source)
    if entry is not None and entry[0] == thread and entry[1] == outcome and entry[2] == target:
        return entry
    if not _plain(path, thread, source, outcome, target):
        return None
    q = encode_basestring
    entry = _cache_in(_cache_in(_TRANSITIONS).setdefault(path, {}))[source] = (
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
    key = (capture[0], capture[1])
    rest = capture[3:]
    entry = _CONTAINERS.get(key)
    if entry is not None and entry[0] == rest:
        return entry
    line = _capture_line((capture[0], capture[1], 0.0, *rest))
    head, found, tail = line.partition('"time": 0.000000000')
    if not found:
        raise ValueError("no time in the line")  # not expected: the general path then
    entry = _cache_in(_CONTAINERS)[key] = (rest, head + '"time": ', tail)
    return entry


_PARTS: dict[type[Event], Callable[[Capture], tuple[Any, ...] | None]] = {
    StateEntered: _entered_parts,
    StateExited: _exited_parts,
    Transition: _transition_parts,
    ContainerStarted: _container_parts,
    ContainerTerminated: _container_parts,
}


def _pair_parts(exited: Capture, moved: Capture) -> _Pair | None:
    """The parts of a state_exited line and of the transition line that follows it:
    the strings they were made of, then the text before, between and after the times
    (made and cached; :func:`_step_text` looks them up)."""
    _, path, _, thread, label, outcome = exited
    container, target = moved[1], moved[6]
    out = _exited_parts(exited)
    into = _transition_parts(moved)
    if out is None or into is None:
        return None
    entry = _cache_in(_PAIRS)[path] = (
        thread,
        label,
        outcome,
        container,
        target,
        out[3],
        out[4] + into[3],
        into[4],
    )
    return entry


def _step_text(
    step: tuple[Capture, ...], known: set[str] | None
) -> tuple[str, tuple[Any, ...]] | None:
    """The template and arguments of the lines of a state machine's step, or None.

    A step is state_exited + transition (+ state_entered of the next state), all from
    one thread, the first two at one time, captured together; anything else is None.
    """
    exited, moved = step[0], step[1]
    _, path, t, thread, label, outcome = exited
    if not (
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
        return None
    pair = _PAIRS.get(path)
    if (
        pair is None
        or pair[0] != thread
        or pair[1] != label
        or pair[2] != outcome
        or pair[3] != moved[1]
        or pair[4] != moved[6]
    ):
        pair = _pair_parts(exited, moved)
        if pair is None:
            return None
    if len(step) == 2:
        return _PAIR, (pair[5], t, pair[6], t, pair[7])
    _, _, entered = step  # three: the next state's state_entered
    _, next_path, t_next, next_thread, next_label = entered
    if not (
        entered[0] is StateEntered
        and next_thread is thread
        and next_label == moved[6]
        and type(t_next) is float
        and t_next - t_next == 0.0
        and (known is None or next_path in known)
    ):
        return None
    into = _entered_parts(entered)
    if into is None:
        return None
    return _STEP, (pair[5], t, pair[6], t, pair[7], into[2], t_next, into[3])


def lines_of(
    items: list[Any],
    known: set[str] | None,
    new_path: Callable[[str], str | None],
    structure: Callable[[StructureItem], str],
    rewrite: Callable[[Capture], Capture] | None = None,
) -> tuple[str, int]:
    """The JSON lines of queued items, in order, and how many of them are events.

    ``new_path(path)`` is asked for every event about a path not in ``known`` (it
    returns a ``structure`` line to write first, or None); ``known`` None: nobody asks.
    ``structure(item)`` gives the line of a :class:`StructureItem` (and updates
    ``known``: the items are taken in order, so an event is checked against the
    structure in force when it happened).

    The events of steps, states and containers are written from cached parts (see
    _ENTERED), their times formatted in one C call for the whole batch: several times
    cheaper than building and encoding a record. Such a line is the one :func:`line_of`
    writes. Any other item, or any surprise (a value that is not a short string, a
    time that is not a finite float), takes :func:`line_of`, after ``rewrite`` (the
    writer's scenes as changes: :mod:`~smach.introspection.scene_changes`).
    """
    template: list[str] = []
    args: list[Any] = []
    timed = template.append
    arg = args.append
    others = 0
    for item in items:
        kind = type(item)
        if kind is not tuple:  # a structure, a record or a line: not an event
            others += 1
            timed("%s")
            arg(structure(item) if kind is StructureItem else line_of(item))
            continue
        if type(item[0]) is tuple:  # captures that came together (capture_many)
            try:
                step = _step_text(item, known)
            except Exception:  # not the usual step
                step = None
            if step is not None:
                timed(step[0])
                args.extend(step[1])
                others -= len(item) - 1  # several events in one item
            else:  # one by one
                text, events = lines_of(list(item), known, new_path, structure, rewrite)
                others -= events - 1
                timed("%s")
                arg(text)
            continue
        if known is not None and item[1] not in known:
            first = new_path(item[1])
            if first is not None:
                timed("%s")
                arg(first)
        try:
            t = item[2]
            split = _PARTS.get(item[0]) if type(t) is float and t - t == 0.0 else None
            parts = None if split is None else split(item)
        except Exception:  # not plain strings
            parts = None
        if parts is None:  # the general path
            timed("%s")
            arg(line_of(item if rewrite is None else rewrite(item)))
        else:
            timed(_TIMED)
            arg(parts[-2])
            arg(t)
            arg(parts[-1])
    return "".join(template) % tuple(args), len(items) - others
