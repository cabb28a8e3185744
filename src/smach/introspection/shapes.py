"""What a laid-out graph is made of: boxes, edges, and the text widths they fit.

:mod:`~smach.introspection.layout` makes a :class:`Layout`;
:mod:`~smach.introspection.svg` draws it. Text is measured with the advance widths of
Arial / Liberation Sans (the page's font), so boxes fit their labels without a
browser.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = [
    "FONT_SIZE",
    "LABEL_H",
    "SMALL_FONT",
    "EdgeShape",
    "Layout",
    "Shape",
    "label_box",
    "text_width",
]

FONT_SIZE = 12.0
SMALL_FONT = 10.0

# Advance widths of Arial (= Liberation Sans) in 1/1000 em, for ASCII 32..126.
_WIDTHS = [
    278, 278, 355, 556, 556, 889, 667, 191, 333, 333, 389, 584, 278, 333, 278, 278,
    556, 556, 556, 556, 556, 556, 556, 556, 556, 556, 278, 278, 584, 584, 584, 556,
    1015, 667, 667, 722, 722, 667, 611, 778, 722, 278, 500, 667, 556, 833, 722, 778,
    667, 778, 722, 667, 611, 722, 667, 944, 667, 667, 611, 278, 278, 278, 469, 556,
    333, 556, 556, 500, 556, 556, 278, 556, 556, 222, 222, 500, 222, 833, 556, 556,
    556, 556, 333, 500, 278, 556, 500, 722, 500, 500, 500, 334, 260, 334, 584,
]  # fmt: skip


def text_width(text: str, size: float = FONT_SIZE, bold: bool = False) -> float:
    """Width of ``text`` in pixels in Arial at ``size`` (a little generous)."""
    units = 0
    for ch in text:
        code = ord(ch)
        units += _WIDTHS[code - 32] if 32 <= code <= 126 else 600
    return units * size / 1000.0 * (1.08 if bold else 1.02)


@dataclass
class Shape:
    """A box: a state, a container (cluster), a collapsed container, or an outcome pill."""

    kind: str
    """``state``, ``container``, ``collapsed`` or ``outcome``."""
    path: str
    label: str
    type: str
    x: float
    y: float
    w: float
    h: float
    depth: int = 0
    count: int = 0
    """States inside a collapsed container."""
    container: str = ""
    """For outcome pills: the container whose outcome this is."""


@dataclass
class EdgeShape:
    """A transition drawn from ``source`` to ``target`` inside ``container``."""

    container: str
    source: str
    outcome: str
    target: str
    terminal: bool
    d: str
    label_x: float
    label_y: float


@dataclass
class Layout:
    """A laid-out graph: its size, its boxes (a container before what it holds), its edges."""

    width: float
    height: float
    shapes: list[Shape] = field(default_factory=list)
    edges: list[EdgeShape] = field(default_factory=list)


LABEL_H = 13.0
"""Height of an edge label's box (10 px text and its white halo)."""


def label_box(edge: EdgeShape) -> tuple[float, float, float, float]:
    """(left, top, right, bottom) of the label of ``edge`` (drawn centred on its point)."""
    half = (text_width(edge.outcome, SMALL_FONT) + 6) / 2
    return (
        edge.label_x - half,
        edge.label_y - LABEL_H / 2,
        edge.label_x + half,
        edge.label_y + LABEL_H / 2,
    )
