"""The fast lines of a journal (lines_of) are the general ones (line_of), item by item."""

from __future__ import annotations

import json
import random
from collections.abc import Callable
from typing import Any

import pytest

from smach.introspection import events as ev
from smach.introspection.journal_lines import StructureItem, line_of, lines_of

NAMES = ["A", "B", 'é"x', "long" * 100]


def step(rnd: random.Random, t: float) -> tuple[Any, ...]:
    """A state machine's step as captured, now and then not quite the usual one."""
    a, b = rnd.choice(NAMES), rnd.choice(NAMES)
    thread = "T" if rnd.random() < 0.9 else "U"
    outcome = rnd.choice(["done", "é", None])
    exited = (ev.StateExited, "/ROOT/" + a, t, "T", a, outcome if rnd.random() < 0.9 else "done")
    moved = (
        ev.Transition,
        rnd.choice(["/ROOT", "/OTHER"]),
        t if rnd.random() < 0.9 else t + 1.0,
        thread,
        a if rnd.random() < 0.95 else "Z",
        exited[5] if rnd.random() < 0.9 else "other",
        b,
    )
    entered = (ev.StateEntered, "/ROOT/" + b, t + 0.5, "T", b if rnd.random() < 0.9 else "Q")
    return (exited, moved, entered) if rnd.random() < 0.6 else (exited, moved)


def item(rnd: random.Random) -> Any:
    t = rnd.choice([1.5, float("nan"), 3]) if rnd.random() < 0.2 else rnd.random() * 100
    label = rnd.choice(NAMES)
    path = "/ROOT/" + label
    makers: list[Callable[[], Any]] = [
        lambda: step(rnd, t),
        lambda: (ev.StateEntered, path, t, "T", label),
        lambda: (ev.StateExited, path, t, "T", label, rnd.choice(["done", None])),
        lambda: (ev.Transition, "/ROOT", t, "T", label, "done", rnd.choice(NAMES)),
        lambda: (ev.ContainerStarted, "/ROOT", t, "T", "StateMachine", (label,)),
        lambda: (ev.ContainerTerminated, "/ROOT", t, "T", (label,), None),
        lambda: (ev.StateEntered, path, t, "T", 7),  # not a string: the general path
        lambda: {"kind": "note", "x": [1, None]},
        lambda: '{"kind": "raw"}\n',
        lambda: StructureItem("/ROOT", t, None),
    ]
    return rnd.choice(makers)()


def structure_line(item: StructureItem) -> str:
    return json.dumps({"kind": "structure", "time": item.time}) + "\n"


@pytest.mark.parametrize("seed", range(20))
@pytest.mark.parametrize("with_known", [False, True])
def test_lines_of_a_batch_are_line_of_each_capture_in_order(seed: int, with_known: bool) -> None:
    rnd = random.Random(seed)
    items = [item(rnd) for _ in range(200)]
    # Every batch twice: the second time the cached parts of the lines are used.
    for batch in (items, items):
        known = {"/ROOT", "/ROOT/A"} if with_known else None
        expected_known = None if known is None else set(known)

        def new_path(path: str, known: set[str] | None = known) -> str | None:
            assert known is not None
            known.add(path)
            return json.dumps({"kind": "new", "path": path}) + "\n" if len(path) < 20 else None

        expected: list[str] = []
        events = 0
        for one in batch:
            captures = list(one) if type(one) is tuple and type(one[0]) is tuple else [one]
            for capture in captures:
                if type(capture) is StructureItem:
                    expected.append(structure_line(capture))
                    continue
                if type(capture) is tuple:
                    events += 1
                    if expected_known is not None and capture[1] not in expected_known:
                        expected_known.add(capture[1])
                        first = json.dumps({"kind": "new", "path": capture[1]}) + "\n"
                        expected.append(first if len(capture[1]) < 20 else "")
                expected.append(line_of(capture))
        assert lines_of(batch, known, new_path, structure_line) == ("".join(expected), events)
