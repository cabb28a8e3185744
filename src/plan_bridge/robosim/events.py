"""Changes of a pyrobosim world that nobody in the mission makes: a door closed, an
object moved. Each happens at a simulated time (seconds since the mission started).

An events file is a YAML list::

    - at: 4.0              # simulated seconds since the mission started
      close: hall_kitchen_pantry   # open, close, lock or unlock: a hallway or a location
    - at: 20
      move: apple0         # an object ...
      to: table0_tabletop  # ... onto an object spawn (or a location)
    - at: [10, 40]         # a time drawn from the run's seed, between 10 and 40 s
      close: hall_kitchen_office
    - at: [5, 30]
      move: soda
      to: [counter_left, fridge_shelf]   # a spawn drawn from the run's seed
    - at: 12
      remove: apple0       # somebody takes it away
    - at: 15
      add: cup0            # somebody puts a new object ...
      category: cup        # ... of this category (the world's object data) ...
      to: table0_tabletop  # ... onto a spawn (or a location; a list: drawn)

A list of places (``to: [A, B]``) is drawn from the run's seed too, once per event.

A time window ``[LO, HI]`` is drawn once per run, uniformly, from the run's seed
(:meth:`WorldEvent.drawn`): a seeded run repeats, other seeds close the door at other
moments. Items with the same window get the same time (a hallway closed and locked
together).

:func:`load_events` reads one (errors name the file, the item and its line, and what
is allowed); :meth:`~plan_bridge.robosim.world.RobosimWorld.schedule` takes events from
Python. The world applies an event when its clock passes ``at`` (see docs/sim.md).
"""

from __future__ import annotations

import random
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.seeded_time import draw_time, read_time
from plan_bridge.yaml_files import read_yaml_with_lines

__all__ = ["KINDS", "EventError", "WorldEvent", "check_events", "load_events", "parse_events"]

#: What an event does: the key that names it in an events file.
KINDS = ("open", "close", "lock", "unlock", "move", "remove", "add")
_ALLOWED = (
    "each item is a mapping with at: SECONDS and one of open: NAME, close: NAME, lock: NAME, "
    "unlock: NAME (a hallway or location), move: OBJECT with to: SPAWN, remove: OBJECT, or "
    "add: OBJECT with category: CATEGORY and to: SPAWN; at: is seconds or a window [LO, HI] "
    "drawn from the run's seed, to: a spawn or a list of spawns (one drawn from the seed)"
)


class EventError(PlanBridgeError):
    """An events file or event that is malformed or names nothing in the world."""


@dataclass(frozen=True)
class WorldEvent:
    """One change of the world at simulated time ``at``."""

    at: float
    kind: str
    target: str
    to: str | None = None
    origin: str = ""
    """Where it was written (``events.yaml:3``), for messages."""
    window: tuple[float, float] | None = None
    """``at: [LO, HI]``: the time is drawn from the run's seed (:meth:`drawn`); until
    then ``at`` is ``LO``."""
    category: str = ""
    """``add``: the new object's category."""
    choices: tuple[str, ...] = ()
    """``to: [A, B, ...]``: the place is drawn from the run's seed (:meth:`drawn`);
    until then ``to`` is the first."""

    def drawn(self, seed: int) -> WorldEvent:
        """This event at its time for a run with ``seed``: a window's time is drawn
        uniformly in it (the same for every event of that window and seed), and a list
        of places gives one."""
        event = self
        if event.window is not None:
            event = replace(event, at=draw_time(event.window, seed, "world-event"), window=None)
        if event.choices:
            pick = random.Random(f"world-event-to:{seed}:{event.target}:{event.choices!r}")
            event = replace(event, to=pick.choice(event.choices), choices=())
        return event

    def describe(self) -> str:
        where = f" to {self.to}" if self.to else ""
        if self.choices:
            where = f" to one of {', '.join(self.choices)}"
        when = f"{self.at:g} s" if self.window is None else "[{:g}, {:g}] s".format(*self.window)
        return f"{self.kind} {self.target}{where} at {when}"

    def to_json(self) -> dict[str, Any]:
        at: float | list[float] = self.at if self.window is None else list(self.window)
        data: dict[str, Any] = {"at": at, self.kind: self.target}
        if self.choices:
            data["to"] = list(self.choices)
        elif self.to is not None:
            data["to"] = self.to
        if self.category:
            data["category"] = self.category
        return data


def load_events(path: str | Path) -> list[WorldEvent]:
    """The events of a YAML file, in time order (raises :class:`EventError`)."""
    data, lines = read_yaml_with_lines(path, "events", EventError)
    return parse_events(data, str(Path(path)), lines.get("", []))


def parse_events(
    data: Any, origin: str = "events", lines: list[int] | None = None
) -> list[WorldEvent]:
    """Events from YAML data (a list of mappings); ``lines``: each item's line."""
    if data is None:
        return []
    if not isinstance(data, list):
        raise EventError(f"{origin}: the events must be a YAML list; {_ALLOWED}")
    events = []
    for index, item in enumerate(data):
        line = lines[index] if lines and index < len(lines) else None
        where = f"{origin}:{line}" if line is not None else f"{origin}: item {index + 1}"
        events.append(_event(item, where))
    return sorted(events, key=lambda e: e.at)


def _event(item: Any, where: str) -> WorldEvent:
    if not isinstance(item, Mapping):
        raise EventError(f"{where}: {item!r} is not a mapping; {_ALLOWED}")
    keys = (*KINDS, "at", "to", "category")
    unknown = [str(k) for k in item if k not in keys]
    if unknown:
        hint = did_you_mean(unknown[0], keys)
        raise EventError(f"{where}: unknown key {unknown[0]!r}{hint}; {_ALLOWED}")
    at, window = _time(item.get("at"), where)
    kinds = [k for k in KINDS if k in item]
    if len(kinds) != 1:
        said = f"both {kinds[0]} and {kinds[1]}" if kinds else "no change"
        raise EventError(f"{where}: {said}; {_ALLOWED}")
    kind = kinds[0]
    target = item[kind]
    if not isinstance(target, str) or not target:
        raise EventError(
            f"{where}: {kind}: must name a hallway, location or object, got {target!r}"
        )
    to = item.get("to")
    choices: tuple[str, ...] = ()
    if kind in ("move", "add"):
        if isinstance(to, list) and to and all(isinstance(t, str) and t for t in to):
            choices = tuple(to)
            to = choices[0]
        elif not isinstance(to, str) or not to:
            raise EventError(
                f"{where}: {kind}: {target} needs to: SPAWN (where the object goes) or a "
                f"list of spawns"
            )
    elif to is not None:
        raise EventError(f"{where}: to: goes with move: and add: only; {_ALLOWED}")
    category = item.get("category", "")
    if kind == "add" and (not isinstance(category, str) or not category):
        raise EventError(f"{where}: add: {target} needs category: (the new object's category)")
    if kind != "add" and "category" in item:
        raise EventError(f"{where}: category: goes with add: only; {_ALLOWED}")
    return WorldEvent(at, kind, target, to, where, window, category, choices)


def _time(at: Any, where: str) -> tuple[float, tuple[float, float] | None]:
    """``at:`` as (seconds, window): a number, or a window ``[LO, HI]``."""
    time = read_time(at)
    if isinstance(time, str):
        raise EventError(f"{where}: {time}; {_ALLOWED}")
    return time


def check_events(
    events: Iterable[WorldEvent],
    gates: Iterable[str],
    objects: Iterable[str],
    spawns: Iterable[str],
) -> None:
    """Every name of ``events`` exists in the world (raises :class:`EventError`)."""
    gate_names, object_names = set(gates), set(objects)
    places = {*spawns, *gate_names}
    # Objects added by an event may be moved and removed by later ones.
    added = {e.target for e in events if e.kind == "add"}
    for event in events:
        if event.kind in ("move", "add"):
            for to in event.choices or (event.to,):
                if to not in places:
                    hint = did_you_mean(str(to), places)
                    raise EventError(
                        f"{event.origin}: to: no object spawn or location {to!r}{hint}"
                    )
        if event.kind == "add":
            if event.target in object_names or event.target in gate_names:
                raise EventError(
                    f"{event.origin}: add: {event.target!r} is already a name of the world"
                )
        elif event.kind in ("move", "remove"):
            if event.target not in object_names and event.target not in added:
                hint = did_you_mean(event.target, object_names)
                raise EventError(f"{event.origin}: {event.kind}: no object {event.target!r}{hint}")
        elif event.target not in gate_names:
            hint = did_you_mean(event.target, gate_names)
            raise EventError(
                f"{event.origin}: {event.kind}: no hallway or location {event.target!r}{hint}"
            )
