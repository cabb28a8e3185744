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

from smach.introspection.layout import Layout, Shape, layout, text_width
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
    hidden_active: set[str] = set()
    collapsed_paths = [s.path for s in lay.shapes if s.kind == "collapsed"]
    for path in active_set:
        for c in collapsed_paths:
            if path.startswith(c + "/"):
                hidden_active.add(c)

    out: list[str] = []
    w, h = lay.width, lay.height
    out.append(
        f'<svg xmlns="http://www.w3.org/2000/svg" class="smach-graph" '
        f'viewBox="0 0 {w:.0f} {h:.0f}" width="{w:.0f}" height="{h:.0f}">'
    )
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

    badges: list[str] = []
    out.append('<g class="clusters">')
    for s in lay.shapes:
        if s.kind != "container":
            continue
        extra = []
        if s.path in active_set:
            extra.append("active")
        if s.path in preempt_set:
            extra.append("preempt")
            badges.append(_badge(s))
        if s.path in error_set:
            extra.append("error")
        out.append(
            f'<g class="{_classes("cluster", s, extra)}" data-path={quoteattr(s.path)}>'
            f"<title>{escape(s.path)} ({escape(s.type)})</title>"
            f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="10"/>'
        )
        tx = s.x + 12
        if s.depth > 0:
            out.append(
                f'<text class="toggle" data-toggle={quoteattr(s.path)} x="{s.x + 10:.1f}" '
                f'y="{s.y + 13:.1f}">\u2212</text>'
            )
            tx += 14
        out.append(
            f'<text class="ctitle" x="{tx:.1f}" y="{s.y + 13:.1f}">{escape(s.label)}'
            f'<tspan class="ctype" dx="8">{escape(s.type)}</tspan></text></g>'
        )
    out.append("</g>")

    out.append('<g class="edges">')
    for e in lay.edges:
        is_taken = list(taken.get(e.container, ()))[:2] == [e.source, e.outcome]
        cls = "edge taken" if is_taken else "edge"
        marker = "arrow-taken" if is_taken else "arrow"
        out.append(
            f'<g class="{cls}" data-container={quoteattr(e.container)} '
            f"data-source={quoteattr(e.source)} data-outcome={quoteattr(e.outcome)}>"
            f'<path d="{e.d}" marker-end="url(#{marker})"/>'
            f'<text x="{e.label_x:.1f}" y="{e.label_y:.1f}" text-anchor="middle">'
            f"{escape(e.outcome)}</text></g>"
        )
    out.append("</g>")

    out.append('<g class="nodes">')
    for s in lay.shapes:
        if s.kind == "container":
            continue
        cx, cy = s.x + s.w / 2, s.y + s.h / 2
        if s.kind == "outcome":
            cls = "outcome reached" if s.path in reached_set else "outcome"
            out.append(
                f'<g class="{cls}" data-path={quoteattr(s.path)}>'
                f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="10"/>'
                f'<text class="label" x="{cx:.1f}" y="{cy:.1f}" text-anchor="middle">'
                f"{escape(s.label)}</text></g>"
            )
            continue
        extra = []
        if s.path in active_set:
            extra.append("active")
        if s.path in hidden_active:
            extra.append("contains-active")
        if s.path in preempt_set:
            extra.append("preempt")
            badges.append(_badge(s))
        if s.path in error_set:
            extra.append("error")
        if s.path in outcomes:
            extra.append("visited")
        base = "node collapsed" if s.kind == "collapsed" else "node state"
        toggle = f" data-toggle={quoteattr(s.path)}" if s.kind == "collapsed" else ""
        sub = f"▸ {s.count} states" if s.kind == "collapsed" else ""
        if s.path in outcomes and s.kind != "collapsed":
            sub = f"→ {outcomes[s.path]}"
        out.append(
            f'<g class="{_classes(base, s, extra)}" data-path={quoteattr(s.path)}{toggle}>'
            f"<title>{escape(s.path)} ({escape(s.type)})</title>"
            f'<rect x="{s.x:.1f}" y="{s.y:.1f}" width="{s.w:.1f}" height="{s.h:.1f}" rx="7"/>'
            f'<text class="label" x="{cx:.1f}" y="{cy - 6:.1f}" text-anchor="middle">'
            f"{escape(s.label)}</text>"
            f'<text class="sub" x="{cx:.1f}" y="{cy + 9:.1f}" text-anchor="middle">'
            f"{escape(sub)}</text></g>"
        )
    out.append("</g>")
    if badges:
        out.append('<g class="badges">' + "".join(badges) + "</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


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
