"""Draw a :mod:`~smach.introspection.layout` as SVG (the page and the export share it).

Every box carries ``data-path`` (edges ``data-container``, ``data-source`` and
``data-outcome``) so the live page can highlight states by toggling classes. The
standalone export embeds the page's graph stylesheet and, when given a view (a
journal at some time), the classes of that moment.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from importlib import resources
from xml.sax.saxutils import escape, quoteattr

from smach.introspection.layout import layout
from smach.introspection.shapes import EdgeShape, Layout, Shape, text_width
from smach.introspection.structure import StateNode

__all__ = ["graph_css", "render_svg"]


def graph_css() -> str:
    """The graph stylesheet (``static/graph.css``)."""
    return (resources.files("smach.introspection") / "static" / "graph.css").read_text("utf-8")


def _classes(base: str, shape: Shape, extra: Collection[str]) -> str:
    names = [base, f"t-{shape.type}", f"d{min(shape.depth, 3)}", *extra]
    return " ".join(names)


def render_svg(
    root: StateNode,
    *,
    collapsed: Collection[str] = (),
    active: Collection[str] = (),
    outcomes: Mapping[str, str] | None = None,
    preempt: Collection[str] = (),
    errors: Collection[str] = (),
    taken: Mapping[str, tuple[str, str] | list[str]] | None = None,
    reached: Collection[str] = (),
    standalone: bool = True,
    title: str | None = None,
) -> str:
    """SVG text of ``root``.

    ``active``, ``preempt`` and ``errors`` are state paths to mark; ``outcomes`` maps
    paths to their last outcome (shown under the label); ``taken`` maps a container
    path to the ``(source, outcome)`` of its last transition; ``reached`` lists
    outcome pills (``container:outcome``) to mark as returned.
    """
    lay: Layout = layout(root, collapsed)
    active_set = set(active)
    preempt_set = set(preempt)
    error_set = set(errors)
    reached_set = set(reached)
    outcomes = outcomes or {}
    taken = taken or {}
    # The classes a box gets, in this order, for being in each collection of paths.
    cluster_marks: list[tuple[str, Collection[str]]] = [
        ("active", active_set),
        ("preempt", preempt_set),
        ("error", error_set),
    ]
    node_marks: list[tuple[str, Collection[str]]] = [
        ("active", active_set),
        ("contains-active", _hidden_active(lay, active_set)),
        ("preempt", preempt_set),
        ("error", error_set),
        ("visited", outcomes),
    ]
    clusters = [s for s in lay.shapes if s.kind == "container"]
    nodes = [s for s in lay.shapes if s.kind != "container"]

    out = _head(lay, title, standalone)
    out.append('<g class="clusters">')
    out.extend(_cluster(s, _marked(s, cluster_marks)) for s in clusters)
    out.append("</g>")
    out.append('<g class="edges">')
    out.extend(
        _edge(e, list(taken.get(e.container, ()))[:2] == [e.source, e.outcome]) for e in lay.edges
    )
    out.append("</g>")
    out.append('<g class="nodes">')
    for s in nodes:
        if s.kind == "outcome":
            out.append(_pill(s, s.path in reached_set))
        else:
            out.append(_node(s, _marked(s, node_marks), outcomes))
    out.append("</g>")
    badges = [_badge(s) for s in clusters if s.path in preempt_set]
    badges += [_badge(s) for s in nodes if s.kind != "outcome" and s.path in preempt_set]
    if badges:
        out.append('<g class="badges">' + "".join(badges) + "</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _marked(s: Shape, marks: list[tuple[str, Collection[str]]]) -> list[str]:
    """The names of the ``marks`` whose paths hold the path of ``s``."""
    return [name for name, paths in marks if s.path in paths]


def _hidden_active(lay: Layout, active: Collection[str]) -> set[str]:
    """The collapsed containers that hold an active state."""
    collapsed_paths = [s.path for s in lay.shapes if s.kind == "collapsed"]
    return {c for path in active for c in collapsed_paths if path.startswith(c + "/")}


def _head(lay: Layout, title: str | None, standalone: bool) -> list[str]:
    """The opening of the picture: the ``<svg>`` tag, the title, arrow heads and style."""
    w, h = lay.width, lay.height
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" class="smach-graph" '
        f'viewBox="0 0 {w:.0f} {h:.0f}" width="{w:.0f}" height="{h:.0f}">'
    ]
    if title:
        out.append(f"<title>{escape(title)}</title>")
    out.append("<defs>")
    for mid in ("arrow", "arrow-taken"):
        out.append(
            f'<marker id="{mid}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="9" '
            f'markerHeight="9" markerUnits="userSpaceOnUse" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z"/></marker>'
        )
    if standalone:
        out.append(f"<style>{graph_css()}</style>")
    out.append("</defs>")
    if standalone:
        out.append(f'<rect x="0" y="0" width="{w:.0f}" height="{h:.0f}" fill="#ffffff"/>')
    return out


def _cluster(s: Shape, extra: Collection[str]) -> str:
    """An expanded container: its frame, its fold toggle (below the root) and its title."""
    tx = s.x + 12
    toggle = ""
    if s.depth > 0:
        toggle = (
            f'\n<text class="toggle" data-toggle={quoteattr(s.path)} x="{s.x + 10:.1f}" '
            f'y="{s.y + 13:.1f}">\u2212</text>'
        )
        tx += 14
    return (
        f'<g class="{_classes("cluster", s, extra)}" data-path={quoteattr(s.path)}>'
        f"<title>{escape(s.path)} ({escape(s.type)})</title>"
        f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="10"/>'
        f"{toggle}\n"
        f'<text class="ctitle" x="{tx:.1f}" y="{s.y + 13:.1f}">{escape(s.label)}'
        f'<tspan class="ctype" dx="8">{escape(s.type)}</tspan></text></g>'
    )


def _edge(e: EdgeShape, taken: bool) -> str:
    """A transition: its path and its outcome label (``taken``: the last one taken)."""
    cls = "edge taken" if taken else "edge"
    marker = "arrow-taken" if taken else "arrow"
    return (
        f'<g class="{cls}" data-container={quoteattr(e.container)} '
        f"data-source={quoteattr(e.source)} data-outcome={quoteattr(e.outcome)}>"
        f'<path d="{e.d}" marker-end="url(#{marker})"/>'
        f'<text x="{e.label_x:.1f}" y="{e.label_y:.1f}" text-anchor="middle">'
        f"{escape(e.outcome)}</text></g>"
    )


def _pill(s: Shape, reached: bool) -> str:
    """A container's outcome (``reached``: the container returned it)."""
    cx, cy = s.x + s.w / 2, s.y + s.h / 2
    cls = "outcome reached" if reached else "outcome"
    return (
        f'<g class="{cls}" data-path={quoteattr(s.path)}>'
        f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="10"/>'
        f'<text class="label" x="{cx:.1f}" y="{cy:.1f}" text-anchor="middle">'
        f"{escape(s.label)}</text></g>"
    )


def _node(s: Shape, extra: Collection[str], outcomes: Mapping[str, str]) -> str:
    """A state, or a collapsed container (with its count of states and its toggle)."""
    cx, cy = s.x + s.w / 2, s.y + s.h / 2
    folded = s.kind == "collapsed"
    base = "node collapsed" if folded else "node state"
    toggle = f" data-toggle={quoteattr(s.path)}" if folded else ""
    sub = f"▸ {s.count} states" if folded else ""
    if s.path in outcomes and not folded:
        sub = f"→ {outcomes[s.path]}"
    return (
        f'<g class="{_classes(base, s, extra)}" data-path={quoteattr(s.path)}{toggle}>'
        f"<title>{escape(s.path)} ({escape(s.type)})</title>"
        f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="7"/>'
        f'<text class="label" x="{cx:.1f}" y="{cy - 6:.1f}" text-anchor="middle">'
        f"{escape(s.label)}</text>"
        f'<text class="sub" x="{cx:.1f}" y="{cy + 9:.1f}" text-anchor="middle">'
        f"{escape(sub)}</text></g>"
    )


BADGE_TEXT = "PREEMPT REQUESTED"
BADGE_W = text_width(BADGE_TEXT, 9, bold=True) + 12


def _badge(s: Shape) -> str:
    x, y = s.x + s.w / 2 - BADGE_W / 2, s.y - 9
    if s.kind == "container":
        x = s.x + s.w - BADGE_W - 8
    return (
        f'<g class="badge" data-for={quoteattr(s.path)}><rect x="{x:.1f}" y="{y:.1f}" '
        f'width="{BADGE_W:.1f}" height="15" rx="7"/><text x="{x + BADGE_W / 2:.1f}" '
        f'y="{y + 7.5:.1f}" text-anchor="middle">{BADGE_TEXT}</text></g>'
    )
