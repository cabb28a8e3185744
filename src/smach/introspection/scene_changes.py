"""Scenes in a journal as changes: a picture of the world costs what moved in it.

A ``scene`` event holds a whole SVG picture of the world (the map, the robots, their
trails): 10-25 KB, written after every step of a mission that shows its world, most of
it the same map as before. The journal writes a scene as the lines that changed since
the previous scene of the same journal (``svg_change``: ``[[start, stop, lines], ...]``
replacing ``previous[start:stop]``, in order) and, the first time and every
:data:`WHOLE_EVERY` th scene, whole (``svg``). Readers (:func:`~.journal.read_journal`,
the viewer's journal source) give the records back with ``svg`` whole:
:class:`SceneText` rebuilds it. A picture drawn one element per line (as
``plan_bridge.robosim.picture`` draws) changes in a few lines from one step to the next.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, ClassVar

from smach.events import Capture, Event, SceneChanged
from smach.summary import Summary

__all__ = ["WHOLE_EVERY", "SceneChange", "SceneChanges", "SceneText"]

#: Every this many scenes one is written whole (a reader needs nothing older).
WHOLE_EVERY = 100


@dataclass(slots=True, kw_only=True)
class SceneChange(Event):
    """A ``scene`` record as written: the lines that changed since the last scene."""

    kind: ClassVar[str] = "scene"
    svg_change: list[list[Any]]
    title: str = ""


class SceneChanges:
    """The writer's side: scene captures become changes (one per journal writer)."""

    def __init__(self) -> None:
        self._last: list[str] | None = None
        self._since_whole = 0

    def capture(self, capture: Capture) -> Capture:
        """``capture`` as the journal writes it: a scene as a change when it can be,
        any other capture as it is."""
        if capture[0] is not SceneChanged:
            return capture
        _, path, time, thread, svg, title = capture
        text = svg.value if isinstance(svg, Summary) else svg
        if not isinstance(text, str):
            return capture
        lines = text.split("\n")
        last, self._last = self._last, lines
        if last is None or self._since_whole + 1 >= WHOLE_EVERY:
            self._since_whole = 0
            return capture
        self._since_whole += 1
        matcher = difflib.SequenceMatcher(None, last, lines, autojunk=False)
        change = [
            [i1, i2, lines[j1:j2]]
            for tag, i1, i2, j1, j2 in matcher.get_opcodes()
            if tag != "equal"
        ]
        return (SceneChange, path, time, thread, Summary(change), title)


class SceneText:
    """The reader's side: ``scene`` records given back whole (one per journal read)."""

    def __init__(self) -> None:
        self._last: list[str] | None = None

    def record(self, record: dict[str, Any]) -> dict[str, Any]:
        """``record`` with a scene's ``svg`` whole (others as they are). A change with no
        scene before it (a journal cut at its start) is left as it is."""
        if record.get("kind") != "scene":
            return record
        svg = record.get("svg")
        if isinstance(svg, str):
            self._last = svg.split("\n")
            return record
        change = record.get("svg_change")
        if not isinstance(change, list) or self._last is None:
            return record
        lines = list(self._last)
        # Later parts first: each part's indexes are those of the previous picture.
        for start, stop, new in reversed(change):
            lines[start:stop] = new
        self._last = lines
        whole = {k: v for k, v in record.items() if k != "svg_change"}
        whole["svg"] = "\n".join(lines)
        return whole
