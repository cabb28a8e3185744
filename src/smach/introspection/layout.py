"""Lay out a structure snapshot for drawing: our own layered layout, no Graphviz.

The same layout feeds the live page (the server sends the SVG it draws) and the
static SVG export, so what a test or a screenshot sees is what ``to_svg`` writes.

Each container is laid out on its own, bottom-up: children are ranked by the
longest path from the initial state (back edges ignored), a rank with many states
(a Concurrence) is split into rows, and a long chain is wrapped into columns so that
50 or 1000 states still fit a screen. The container's outcomes sit in a row at its
bottom; an edge leaving a nested container starts at the outcome it returned.
Collapsed containers are drawn as one box.

Boxes are sized to their labels by :func:`~smach.introspection.shapes.text_width`;
the shapes a layout is made of are in :mod:`~smach.introspection.shapes`.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Collection, Iterator
from dataclasses import dataclass, field

from smach.introspection.shapes import (
    FONT_SIZE,
    LABEL_H,
    SMALL_FONT,
    EdgeShape,
    Layout,
    Shape,
    label_box,
    text_width,
)
from smach.introspection.structure import Edge, StateNode

__all__ = ["EdgeShape", "Layout", "Shape", "label_box", "layout", "off_path", "text_width"]

NODE_H = 40.0
NODE_MIN_W = 76.0
NODE_PAD = 14.0
HEADER = 26.0
PAD = 14.0
GAP_X = 28.0
GAP_Y = 42.0
OUTCOME_H = 20.0
OUTCOME_GAP = 10.0
MAX_PER_ROW = 6
MIN_ROWS_PER_COLUMN = 8
TALL = 700.0  # a stack of rows taller than this (and than wide) wraps into columns


@dataclass
class _Block:
    """A laid-out subtree with coordinates relative to its own top-left corner."""

    w: float
    h: float
    shapes: list[Shape]
    edges: list[EdgeShape]
    pills: dict[str, Shape] = field(default_factory=dict)
    """For an expanded container: its outcome pills by outcome (relative coordinates)."""
    box: Shape | None = None


def _count(node: StateNode) -> int:
    return sum(1 for _ in node.walk()) - 1


def _leaf(node: StateNode, depth: int, collapsed: bool) -> _Block:
    sub = f"▸ {_count(node)} states" if collapsed else ""
    w = max(
        NODE_MIN_W,
        text_width(node.label, FONT_SIZE, bold=True) + 2 * NODE_PAD,
        text_width(sub, SMALL_FONT) + 2 * NODE_PAD,
    )
    shape = Shape(
        "collapsed" if collapsed else "state",
        node.path,
        node.label,
        node.type,
        0.0,
        0.0,
        w,
        NODE_H,
        depth,
        _count(node) if collapsed else 0,
    )
    return _Block(w, NODE_H, [shape], [], box=shape)


def _ranks(node: StateNode) -> dict[str, int]:
    labels = [c.label for c in node.children]
    succ: dict[str, list[str]] = {label: [] for label in labels}
    for edge in node.edges:
        if not edge.terminal and edge.source in succ and edge.target in succ:
            succ[edge.source].append(edge.target)
    # Depth-first from the initial states (then any state not reached) to find the
    # back edges; the longest path over the remaining edges gives the rank.
    order: list[str] = []
    state: dict[str, int] = {}
    back: set[tuple[str, str]] = set()
    starts = [s for s in node.initial_states if s in succ] + labels
    for start in starts:
        if start in state:
            continue
        stack: list[tuple[str, int]] = [(start, 0)]
        state[start] = 1
        while stack:
            v, i = stack[-1]
            if i < len(succ[v]):
                stack[-1] = (v, i + 1)
                w = succ[v][i]
                if state.get(w) == 1:
                    back.add((v, w))
                elif w not in state:
                    state[w] = 1
                    stack.append((w, 0))
            else:
                stack.pop()
                state[v] = 2
                order.append(v)
    rank = dict.fromkeys(labels, 0)
    for v in reversed(order):
        for w in succ[v]:
            if (v, w) not in back and rank[w] < rank[v] + 1:
                rank[w] = rank[v] + 1
    return rank


def _container(node: StateNode, collapsed: Collection[str], depth: int) -> _Block:
    """The block of an expanded container: its children's blocks in rows and columns,
    its outcome pills in a row at the bottom, and the edges of its transitions."""
    blocks = {child.label: _block(child, collapsed, depth + 1) for child in node.children}
    top = HEADER + PAD
    placed, content_w, content_h = _place(_columns(_rows(node), blocks), blocks, top)

    pill_ws = [max(46.0, text_width(o, SMALL_FONT) + 18) for o in node.outcomes]
    pills_w = sum(pill_ws) + OUTCOME_GAP * max(0, len(pill_ws) - 1)
    title_w = text_width(f"{node.label}  {node.type}", FONT_SIZE, bold=True) + 40
    inner_w = max(content_w, pills_w, title_w, NODE_MIN_W)
    w = inner_w + 2 * PAD
    pill_y = top + content_h + (GAP_Y if node.children else 0)
    h = pill_y + OUTCOME_H + PAD

    # Centre the content if the container is wider than it (long titles, many pills).
    shift = (inner_w - content_w) / 2
    placed = {label: (bx + shift, by, block) for label, (bx, by, block) in placed.items()}

    box = Shape("container", node.path, node.label, node.type, 0.0, 0.0, w, h, depth)
    shapes = [box, *_pills(node, pill_ws, PAD + (inner_w - pills_w) / 2, pill_y, depth)]
    pills = {pill.label: pill for pill in shapes[1:]}
    edges: list[EdgeShape] = []
    for bx, by, block in placed.values():
        shapes.extend(_moved(s, bx, by) for s in block.shapes)
        edges.extend(_moved_edge(e, bx, by) for e in block.edges)
    lanes: dict[str, float] = {}
    own = _edges(node, placed, pills, lanes)
    edges.extend(own)
    _separate_labels(edges, len(edges) - len(own))
    # Back edges and lanes may reach out on the right: make room.
    reach = [e.label_x + 30 for e in own] + [lane + PAD for lane in lanes.values()]
    w += max(0.0, max(reach, default=w) - w)
    box.w = w
    return _Block(w, h, shapes, edges, pills, box)


def _rows(node: StateNode) -> list[list[str]]:
    """The children's labels in rows: ranks top to bottom, each ordered by its
    predecessors' positions and cut into rows of :data:`MAX_PER_ROW`."""
    rank = _ranks(node)
    by_rank: dict[int, list[str]] = {}
    for child in node.children:
        by_rank.setdefault(rank[child.label], []).append(child.label)
    preds: dict[str, list[str]] = {c.label: [] for c in node.children}
    for edge in node.edges:
        if not edge.terminal and edge.target in preds and edge.source in preds:
            preds[edge.target].append(edge.source)
    rows: list[list[str]] = []
    position: dict[str, float] = {}
    for r in sorted(by_rank):
        members = by_rank[r]
        members.sort(
            key=lambda lb: (
                sum(position[p] for p in preds[lb] if p in position)
                / max(1, sum(1 for p in preds[lb] if p in position))
                if any(p in position for p in preds[lb])
                else 1e9
            )
        )
        for start in range(0, len(members), MAX_PER_ROW):
            row = members[start : start + MAX_PER_ROW]
            for i, label in enumerate(row):
                position[label] = i - (len(row) - 1) / 2
            rows.append(row)
    return rows


_Placed = dict[str, tuple[float, float, _Block]]
"""Where each child's block goes: label -> (x, y, block), relative to the container."""


def _place(
    columns: list[list[list[str]]], blocks: dict[str, _Block], top: float
) -> tuple[_Placed, float, float]:
    """The place of each block, columns left to right and rows centred in their column,
    and the width and height of them all."""
    placed: _Placed = {}
    x = PAD
    content_h = 0.0
    for column in columns:
        col_w = max(
            (sum(blocks[lb].w for lb in row) + GAP_X * (len(row) - 1) for row in column),
            default=0.0,
        )
        y = top
        for row in column:
            row_w = sum(blocks[lb].w for lb in row) + GAP_X * (len(row) - 1)
            row_h = max(blocks[lb].h for lb in row)
            cx = x + (col_w - row_w) / 2
            for label in row:
                placed[label] = (cx, y, blocks[label])
                cx += blocks[label].w + GAP_X
            y += row_h + GAP_Y
        content_h = max(content_h, y - GAP_Y - top)
        x += col_w + GAP_X * 1.6
    return placed, max(0.0, x - GAP_X * 1.6 - PAD), content_h


def _pills(node: StateNode, widths: list[float], x: float, y: float, depth: int) -> list[Shape]:
    """The outcome pills of ``node`` in a row from ``(x, y)``."""
    pills = []
    for outcome, pw in zip(node.outcomes, widths, strict=True):
        pills.append(
            Shape(
                "outcome",
                f"{node.path}:{outcome}",
                outcome,
                "outcome",
                x,
                y,
                pw,
                OUTCOME_H,
                depth,
                container=node.path,
            )
        )
        x += pw + OUTCOME_GAP
    return pills


_Anchor = tuple[float, float, float, float]
"""Where an edge meets a box: ``(x, y)`` on its bottom (a source) or top (a target),
and ``(right, mid)`` on its right-hand side, for loops and back edges."""


def _edges(
    node: StateNode, placed: _Placed, pills: dict[str, Shape], lanes: dict[str, float]
) -> list[EdgeShape]:
    """The edges of the transitions of ``node`` between its placed children and pills."""
    out_count: dict[str, int] = {}
    for edge in node.edges:
        if edge.source in placed:
            out_count[edge.source] = out_count.get(edge.source, 0) + 1
    out_seen: dict[str, int] = {}
    boxes = _Boxes(placed)
    edges: list[EdgeShape] = []
    for edge in node.edges:
        if edge.source not in placed:
            continue
        k = out_seen.get(edge.source, 0)
        out_seen[edge.source] = k + 1
        source = placed[edge.source]
        start = _leaving(source, edge.outcome, k, out_count[edge.source])
        end = _arriving(edge, placed, pills)
        if end is None:
            continue
        d, lx, ly = _curve(edge, start, end, source[2].w, boxes, lanes)
        edges.append(
            EdgeShape(node.path, edge.source, edge.outcome, edge.target, edge.terminal, d, lx, ly)
        )
    return edges


def _leaving(source: tuple[float, float, _Block], outcome: str, k: int, m: int) -> _Anchor:
    """Where the ``k``-th of ``m`` edges leaving ``source`` starts: the pill of its outcome
    (a container), else spread along its bottom."""
    sx0, sy0, sblock = source
    pill = sblock.pills.get(outcome)
    if pill is not None:
        return (
            sx0 + pill.x + pill.w / 2,
            sy0 + pill.y + pill.h,
            sx0 + sblock.w,
            sy0 + pill.y + pill.h / 2,
        )
    return sx0 + sblock.w * (k + 1) / (m + 1), sy0 + sblock.h, sx0 + sblock.w, sy0 + sblock.h / 2


def _arriving(edge: Edge, placed: _Placed, pills: dict[str, Shape]) -> _Anchor | None:
    """Where ``edge`` ends: an outcome pill or a sibling's top; None: neither is drawn."""
    if edge.terminal:
        pill = pills.get(edge.target)
        if pill is None:
            return None
        return pill.x + pill.w / 2, pill.y, pill.x + pill.w, pill.y + pill.h / 2
    if edge.target in placed:
        tx0, ty0, tblock = placed[edge.target]
        return tx0 + tblock.w / 2, ty0, tx0 + tblock.w, ty0 + min(tblock.h / 2, NODE_H / 2)
    return None


def _curve(
    edge: Edge,
    start: _Anchor,
    end: _Anchor,
    source_w: float,
    boxes: _Boxes,
    lanes: dict[str, float],
) -> tuple[str, float, float]:
    """The SVG path of ``edge`` from ``start`` to ``end`` and where its label goes."""
    sx, sy, s_right, s_mid = start
    tx, ty, t_right, t_mid = end
    if edge.source == edge.target and not edge.terminal:
        d = (
            f"M{s_right:.1f},{s_mid - 8:.1f} C{s_right + 40:.1f},{s_mid - 30:.1f} "
            f"{s_right + 40:.1f},{s_mid + 30:.1f} {s_right:.1f},{s_mid + 8:.1f}"
        )
        return d, s_right + 34, s_mid
    if ty > sy + 4 and (lane := _lane(boxes, edge, sx, sy, tx, ty, lanes)) is not None:
        # A long edge would cross the states between: run it down a lane beside them.
        d = (
            f"M{sx:.1f},{sy:.1f} C{sx:.1f},{sy + 16:.1f} {lane:.1f},{sy + 6:.1f} "
            f"{lane:.1f},{sy + 28:.1f} L{lane:.1f},{ty - 28:.1f} C{lane:.1f},{ty - 6:.1f} "
            f"{tx:.1f},{ty - 16:.1f} {tx:.1f},{ty:.1f}"
        )
        return d, lane, sy + 40
    if ty > sy + 4 or (abs(tx - sx) > max(source_w, 60) and ty < sy):
        # Downwards; or into the next column of a wrapped chain: leave downwards, arrive
        # from above.
        dy = max(24.0, (ty - sy) / 2) if ty > sy + 4 else 60
        d = f"M{sx:.1f},{sy:.1f} C{sx:.1f},{sy + dy:.1f} {tx:.1f},{ty - dy:.1f} {tx:.1f},{ty:.1f}"
        return d, *_bezier_mid((sx, sy), (sx, sy + dy), (tx, ty - dy), (tx, ty))
    # Back edge: around the right-hand side.
    bulge = 36 + abs(s_mid - t_mid) * 0.15
    right = max(s_right, t_right)
    d = (
        f"M{s_right:.1f},{s_mid:.1f} C{right + bulge:.1f},{s_mid:.1f} "
        f"{right + bulge:.1f},{t_mid:.1f} {t_right:.1f},{t_mid:.1f}"
    )
    return d, right + bulge * 0.75, (s_mid + t_mid) / 2


def _overlap(a: tuple[float, float, float, float], b: tuple[float, float, float, float]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _separate_labels(edges: list[EdgeShape], first: int) -> None:
    """Move the labels of ``edges[first:]`` (this container's) off every label before them.

    Each label keeps its place if it is free, else takes the nearest free place along
    its edge's direction (below or above first, then beside), so no two labels overlap.
    Boxes are kept in a grid of :data:`_CELL` px squares, so a plan of thousands of
    steps is checked in linear time.
    """
    grid: dict[tuple[int, int], list[tuple[float, float, float, float]]] = {}

    def cells(box: tuple[float, float, float, float]) -> list[tuple[int, int]]:
        return [
            (cx, cy)
            for cx in range(int(box[0] // _CELL), int(box[2] // _CELL) + 1)
            for cy in range(int(box[1] // _CELL), int(box[3] // _CELL) + 1)
        ]

    def free(box: tuple[float, float, float, float]) -> bool:
        return not any(_overlap(box, other) for c in cells(box) for other in grid.get(c, ()))

    def place(box: tuple[float, float, float, float]) -> None:
        for c in cells(box):
            grid.setdefault(c, []).append(box)

    for edge in edges[:first]:
        place(label_box(edge))
    for edge in edges[first:]:
        box = label_box(edge)
        if not free(box):
            width = box[2] - box[0]
            step = LABEL_H + 1
            candidates = [
                (dx * (width + 4), dy * step)
                for ring in range(1, 9)
                for dx, dy in ((0, ring), (0, -ring), (ring, 0), (-ring, 0), (ring, ring))
            ]
            for dx, dy in candidates:
                moved = (box[0] + dx, box[1] + dy, box[2] + dx, box[3] + dy)
                if free(moved):
                    edge.label_x += dx
                    edge.label_y += dy
                    box = moved
                    break
        place(box)


_CELL = 64.0


class _Boxes:
    """The boxes of a container sorted by their top, to find those an edge would cross."""

    def __init__(self, placed: _Placed) -> None:
        self.items = sorted((y, x, b.w, b.h, label) for label, (x, y, b) in placed.items())
        self.tops = [item[0] for item in self.items]
        self.right = max((x + w for _, x, w, _, _ in self.items), default=0.0)

    def between(
        self, source: str, target: str, sy: float, ty: float, lo: float, hi: float
    ) -> Iterator[float]:
        """The right sides of the boxes strictly between ``sy`` and ``ty`` in ``[lo, hi]``."""
        items = self.items
        for i in range(bisect.bisect_right(self.tops, sy), len(items)):
            y, x, w, h, label = items[i]
            if y >= ty:
                return
            if y + h < ty and x < hi and x + w > lo and label not in (source, target):
                yield x + w


def _lane(
    boxes: _Boxes,
    edge: object,
    sx: float,
    sy: float,
    tx: float,
    ty: float,
    lanes: dict[str, float],
) -> float | None:
    """The x of a vertical lane for a downward edge that would cross boxes, if any.

    Edges into the same target share its lane (they merge like a bus), so a plan
    whose every step can abort into one outcome draws one lane, not one per step.
    """
    source = getattr(edge, "source", "")
    target = getattr(edge, "target", "")
    lo, hi = min(sx, tx) - 10, max(sx, tx) + 10
    crossed = boxes.between(source, target, sy, ty, lo, hi)
    first = next(crossed, None)
    if first is None:
        return None
    key = f"{getattr(edge, 'terminal', False)}:{target}"
    shared = lanes.get(key)
    if shared is not None and shared >= max(boxes.right, sx, tx) + 18:
        return shared  # right of every box: no need to look at each
    right = max(first, *crossed, sx, tx)
    if shared is not None and shared >= right + 18:
        return shared
    lane = right + 18
    while any(abs(lane - other) < 12 for k, other in lanes.items() if k != key):
        lane += 12
    lanes[key] = max(lane, shared or 0.0)
    return lanes[key]


def _columns(rows: list[list[str]], blocks: dict[str, _Block]) -> list[list[list[str]]]:
    """Wrap long or tall stacks of rows into columns, aiming at a landscape picture."""
    sizes = [
        (
            sum(blocks[lb].w for lb in row) + GAP_X * (len(row) - 1),
            max(blocks[lb].h for lb in row) + GAP_Y,
        )
        for row in rows
    ]
    total_h = sum(h for _, h in sizes)
    max_w = max((w for w, _ in sizes), default=0.0)
    tall = len(rows) >= 3 and total_h > max(1.5 * max_w, TALL)
    if len(rows) <= MIN_ROWS_PER_COLUMN and not tall:
        return [rows] if rows else [[]]
    area = sum(w * h for w, h in sizes)
    limit = max(*(h for _, h in sizes), math.sqrt(area / 1.5))
    columns: list[list[list[str]]] = [[]]
    height = 0.0
    for row, (_, h) in zip(rows, sizes, strict=True):
        if columns[-1] and height + h > limit:
            columns.append([])
            height = 0.0
        columns[-1].append(row)
        height += h
    return columns


def _bezier_mid(
    p0: tuple[float, float],
    p1: tuple[float, float],
    p2: tuple[float, float],
    p3: tuple[float, float],
) -> tuple[float, float]:
    return (
        (p0[0] + 3 * p1[0] + 3 * p2[0] + p3[0]) / 8,
        (p0[1] + 3 * p1[1] + 3 * p2[1] + p3[1]) / 8,
    )


def _moved(shape: Shape, dx: float, dy: float) -> Shape:
    return Shape(
        shape.kind,
        shape.path,
        shape.label,
        shape.type,
        shape.x + dx,
        shape.y + dy,
        shape.w,
        shape.h,
        shape.depth,
        shape.count,
        shape.container,
    )


def _moved_edge(edge: EdgeShape, dx: float, dy: float) -> EdgeShape:
    parts = []
    for token in edge.d.split(" "):
        cmd = token[0] if token[0].isalpha() else ""  # M, C or L
        xs, ys = token[len(cmd) :].split(",")
        parts.append(f"{cmd}{float(xs) + dx:.1f},{float(ys) + dy:.1f}")
    return EdgeShape(
        edge.container,
        edge.source,
        edge.outcome,
        edge.target,
        edge.terminal,
        " ".join(parts),
        edge.label_x + dx,
        edge.label_y + dy,
    )


def _block(node: StateNode, collapsed: Collection[str], depth: int) -> _Block:
    if not node.is_container:
        return _leaf(node, depth, False)
    if depth > 0 and node.path in collapsed:
        return _leaf(node, depth, True)
    return _container(node, collapsed, depth)


def off_path(root: StateNode, active: Collection[str]) -> list[str]:
    """The containers to collapse so that the ``active`` paths stand out: every
    container two or more levels below ``root`` that holds none of them.

    The root and its children stay open (the overall shape of the machine: a plan's
    chain of steps); below them only the path to what runs is open. The page's default
    view; with nothing active, an overview.
    """
    on_path = set()
    for path in active:
        prefix = path
        while prefix:
            on_path.add(prefix)
            prefix = prefix.rsplit("/", 1)[0]
    shallow = {root.path, *(child.path for child in root.children)}
    return [
        node.path
        for node in root.walk()
        if node.is_container and node.path not in shallow and node.path not in on_path
    ]


def layout(root: StateNode, collapsed: Collection[str] = ()) -> Layout:
    """Coordinates of every box and edge of ``root``; ``collapsed`` container paths are boxes."""
    block = _block(root, set(collapsed), 0)
    margin = 8.0
    shapes = [_moved(s, margin, margin) for s in block.shapes]
    edges = [_moved_edge(e, margin, margin) for e in block.edges]
    return Layout(block.w + 2 * margin, block.h + 2 * margin, shapes, edges)
