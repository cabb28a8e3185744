"""Paths inside one room of a pyrobosim world: straight, or round the furniture.

A route of the map (:mod:`plan_bridge.maps.graph`) is legs inside rooms and through
hallways. A leg inside a room is driven straight when nothing stands in the way;
otherwise round the furniture, on the shortest path over the corners of the
furniture's footprints (grown by the robot's radius, as pyrobosim grows them): a
visibility graph of a few nodes, computed when the leg is driven. pyrobosim's own path
planners are not used: a world-graph planner must connect every pair of its nodes
when the world loads (minutes for a large building), and it plans across the whole
world, hallways the robot has not checked included.

A point inside the furniture (pyrobosim puts a room's navigation pose at its centre,
often inside a table) is left straight for the nearest free point first.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

__all__ = ["free_point", "room_path"]

#: How far off a corner of the grown furniture a path passes (metres).
_CLEARANCE_M = 0.05


def room_path(
    room: Any, start: tuple[float, float], goal: tuple[float, float]
) -> list[tuple[float, float]]:
    """The points of a path from ``start`` to ``goal`` inside pyrobosim room ``room``
    (both ends included); straight when no way round is found."""
    from shapely.geometry import LineString, Point

    free = room.internal_collision_polygon
    if free.is_empty:
        return [start, goal]
    head = [start]
    tail = [goal]
    begin, end = start, goal
    if not free.covers(Point(start)):
        begin = free_point(free, start)
        head.append(begin)
    if not free.covers(Point(goal)):
        end = free_point(free, goal)
        tail.insert(0, end)

    def clear(a: tuple[float, float], b: tuple[float, float]) -> bool:
        return a == b or bool(free.covers(LineString([a, b])))

    if clear(begin, end):
        middle: list[tuple[float, float]] = []
    else:
        found = _shortest(begin, end, _corners(room, free), clear)
        if found is None:
            return [start, goal]
        middle = found[1:-1]
    points = [*head, *middle, *tail]
    return [p for i, p in enumerate(points) if i == 0 or math.dist(p, points[i - 1]) > 1e-6]


def free_point(free: Any, point: tuple[float, float]) -> tuple[float, float]:
    """The point of the free area ``free`` nearest to ``point``, a little inside it."""
    from shapely.geometry import Point
    from shapely.ops import nearest_points

    inner = free.buffer(-_CLEARANCE_M)
    area = inner if not inner.is_empty else free
    nearest = nearest_points(area, Point(point))[0]
    return (float(nearest.x), float(nearest.y))


def _corners(room: Any, free: Any) -> list[tuple[float, float]]:
    """Corners of the room's furniture, grown by the robot's radius and a little more,
    that lie in the free area."""
    from shapely.geometry import Point

    corners: list[tuple[float, float]] = []
    for location in room.locations:
        grown = location.collision_polygon.buffer(_CLEARANCE_M, join_style=2)
        shapes = getattr(grown, "geoms", [grown])
        for shape in shapes:
            for x, y in list(shape.exterior.coords)[:-1]:
                if free.covers(Point(x, y)):
                    corners.append((float(x), float(y)))
    return corners


def _shortest(
    start: tuple[float, float],
    goal: tuple[float, float],
    corners: list[tuple[float, float]],
    clear: Any,
) -> list[tuple[float, float]] | None:
    """Dijkstra over the visibility graph of ``start``, ``goal`` and ``corners``."""
    nodes = [start, goal, *corners]
    best = {0: 0.0}
    before: dict[int, int] = {}
    queue = [(0.0, 0)]
    while queue:
        cost, node = heapq.heappop(queue)
        if node == 1:
            chain = [1]
            while chain[-1] != 0:
                chain.append(before[chain[-1]])
            return [nodes[i] for i in reversed(chain)]
        if cost > best.get(node, math.inf):
            continue
        for other in range(1, len(nodes)):
            if other == node:
                continue
            step = cost + math.dist(nodes[node], nodes[other])
            if step < best.get(other, math.inf) and clear(nodes[node], nodes[other]):
                best[other] = step
                before[other] = node
                heapq.heappush(queue, (step, other))
    return None
