"""The map of a world: a graph of places, and routes over the hallways that are open.

:class:`PlaceMap` is built once per world from its :class:`~.model.WorldModel` (a
networkx graph). Its nodes are the places; two places of one room are joined by a
straight drive (its length: the straight line), and a hallway joins its two doorways
(its length: along its centre line). A route between two places is the shortest path
over the links whose hallway is not closed; the planner sees only its length (one
``navigate`` step), the skill drives it leg by leg.

Which hallways are closed is not the map's: a route is asked for with the hallways
the caller believes closed (the executive's belief, or what the robot has seen). The
shortest paths from a place are computed once per set of closed hallways and kept.
"""

from __future__ import annotations

import itertools
import threading
from collections import OrderedDict
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from typing import Any

import networkx as nx

from plan_bridge.maps.model import WorldModel

__all__ = ["Leg", "PlaceMap", "Route"]

#: Shortest-path trees kept (per source place and set of closed hallways).
_TREES_KEPT = 4096


@dataclass(frozen=True)
class Leg:
    """One stretch of a route: a drive inside a room, or through a hallway."""

    start: str
    end: str
    hall: str | None
    """The hallway it goes through (None: a drive inside a room)."""


@dataclass(frozen=True)
class Route:
    """The way from one place to another."""

    places: tuple[str, ...]
    """The places passed, the first and the last included."""
    legs: tuple[Leg, ...]
    length: float
    """Metres."""

    @property
    def halls(self) -> tuple[str, ...]:
        """The hallways it goes through, in order."""
        return tuple(leg.hall for leg in self.legs if leg.hall is not None)


class PlaceMap:
    """The places of a world and the links between them (see the module's doc)."""

    def __init__(self, model: WorldModel) -> None:
        self.model = model
        graph: nx.Graph[str] = nx.Graph()
        graph.add_nodes_from(model.places)
        by_room: dict[str, list[str]] = {}
        for place in model.places.values():
            by_room.setdefault(place.room, []).append(place.name)
        for room, members in by_room.items():
            if not room:
                continue
            for index, a in enumerate(members):
                for b in members[index + 1 :]:
                    graph.add_edge(a, b, weight=model.distance(a, b), hall=None)
        for hall in model.halls.values():
            a, b = hall.ends
            if a == b:
                continue
            known = graph.get_edge_data(a, b)
            if known is None or known["weight"] > hall.length:
                graph.add_edge(a, b, weight=hall.length, hall=hall.name)
        self.graph = graph
        self._lock = threading.Lock()
        self._trees: OrderedDict[
            tuple[str, frozenset[str]], tuple[dict[str, float], dict[str, list[str]]]
        ] = OrderedDict()

    def __len__(self) -> int:
        return self.graph.number_of_nodes()

    def links(self) -> int:
        """How many links (drives and hallways) the map has."""
        return self.graph.number_of_edges()

    def _tree(
        self, source: str, closed: frozenset[str]
    ) -> tuple[dict[str, float], dict[str, list[str]]]:
        key = (source, closed)
        with self._lock:
            tree = self._trees.get(key)
            if tree is not None:
                self._trees.move_to_end(key)
                return tree

        def weight(u: str, v: str, data: dict[str, Any]) -> float | None:
            return None if data["hall"] in closed else float(data["weight"])

        found: Any = nx.single_source_dijkstra(self.graph, source, weight=weight)
        lengths, paths = found
        tree = (dict(lengths), dict(paths))
        with self._lock:
            self._trees[key] = tree
            while len(self._trees) > _TREES_KEPT:
                self._trees.popitem(last=False)
        return tree

    def route(self, start: str, end: str, closed: Collection[str] = ()) -> Route | None:
        """The shortest way from ``start`` to ``end`` that uses no hallway of
        ``closed`` (None: there is none)."""
        if start not in self.graph or end not in self.graph:
            return None
        lengths, paths = self._tree(start, frozenset(closed))
        if end not in lengths:
            return None
        places = tuple(paths[end])
        pairs = itertools.pairwise(places)
        legs = tuple(Leg(a, b, self.graph.edges[a, b]["hall"]) for a, b in pairs)
        return Route(places, legs, float(lengths[end]))

    def lengths_from(self, start: str, closed: Collection[str] = ()) -> dict[str, float]:
        """Metres from ``start`` to every place it can reach without ``closed``."""
        if start not in self.graph:
            return {}
        return dict(self._tree(start, frozenset(closed))[0])

    def reachable(self, start: str, closed: Collection[str] = ()) -> set[str]:
        """The places a robot at ``start`` can drive to without ``closed``."""
        return set(self.lengths_from(start, closed))

    def halls_between(self, inside: Iterable[str], closed: Collection[str]) -> list[str]:
        """The hallways of ``closed`` that join a place of ``inside`` to one outside."""
        within = set(inside)
        shut = set(closed)
        return sorted(
            hall.name
            for hall in self.model.halls.values()
            if hall.name in shut and (hall.ends[0] in within) != (hall.ends[1] in within)
        )
