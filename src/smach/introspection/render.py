"""Render a structure snapshot as Graphviz DOT, Mermaid text or SVG.

Containers become clusters (DOT) or composite states (Mermaid); each container's
outcomes are drawn as small terminal nodes inside it, so a transition out of a nested
container starts at the outcome it returned. Active states (e.g. from a journal at
a given time) can be highlighted.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Mapping

from smach.introspection.structure import Edge, StateNode

__all__ = ["to_dot", "to_mermaid", "to_svg"]

_ACTIVE = "#ffd54f"
_ACTIVE_STROKE = "#f57f17"
_CONTAINER_FILL = {"StateMachine": "#eef3fb", "Sequence": "#eef3fb", "Concurrence": "#f3eefb"}


def _q(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _outcome_id(container: StateNode, outcome: str) -> str:
    return f"{container.path}:{outcome}"


def _entry(node: StateNode) -> str:
    """The DOT node an edge into ``node`` points at (its first initial leaf)."""
    while node.is_container and node.children:
        by_label = {c.label: c for c in node.children}
        first = node.initial_states[0] if node.initial_states else node.children[0].label
        node = by_label.get(first, node.children[0])
    return node.path


def to_dot(root: StateNode, active: Collection[str] = ()) -> str:
    """Graphviz DOT text for ``root``; paths in ``active`` are filled yellow."""
    lines = [
        "digraph smach {",
        "  compound=true; rankdir=TB; fontname=Helvetica;",
        '  node [fontname=Helvetica, fontsize=11, shape=box, style="rounded,filled", '
        "fillcolor=white];",
        "  edge [fontname=Helvetica, fontsize=9];",
    ]
    _dot_nodes(root, 1, set(active), lines)
    _dot_edges(root, lines)
    lines.append("}")
    return "\n".join(lines) + "\n"


def _dot_nodes(node: StateNode, depth: int, active: set[str], lines: list[str]) -> None:
    """The DOT node of ``node``, or its cluster with everything inside it."""
    pad = "  " * depth
    if not node.is_container:
        fill = _ACTIVE if node.path in active else "white"
        lines.append(f"{pad}{_q(node.path)} [label={_q(node.label)}, fillcolor={_q(fill)}];")
        return
    fill = _CONTAINER_FILL.get(node.type, "#f5f5f5")
    lines.append(f"{pad}subgraph {_q('cluster_' + node.path)} {{")
    if node.path in active:
        # An active container: its frame in the active colour (its inside keeps the
        # container's fill, so the active state inside it still stands out).
        mark = f'style="rounded,filled,bold"; color={_q(_ACTIVE_STROKE)}; penwidth=2.5;'
    else:
        mark = 'style="rounded,filled";'
    lines.append(f"{pad}  label={_q(f'{node.label} ({node.type})')}; {mark} fillcolor={_q(fill)};")
    if not node.children:
        lines.append(f'{pad}  {_q(node.path + ":empty")} [label="(empty)", shape=plaintext];')
    for child in node.children:
        _dot_nodes(child, depth + 1, active, lines)
    for outcome in node.outcomes:
        lines.append(
            f"{pad}  {_q(_outcome_id(node, outcome))} [label={_q(outcome)}, shape=ellipse, "
            'style=filled, fillcolor="#e0e0e0", fontsize=9];'
        )
    lines.append(f"{pad}}}")


def _dot_edges(node: StateNode, lines: list[str]) -> None:
    """The DOT edges of the transitions of ``node`` and of every container inside it."""
    if not node.is_container:
        return
    by_label = {c.label: c for c in node.children}
    for edge in node.edges:
        source = by_label.get(edge.source)
        if source is not None:
            lines.append(_dot_edge(node, by_label, source, edge))
    for child in node.children:
        _dot_edges(child, lines)


def _dot_edge(
    node: StateNode, by_label: Mapping[str, StateNode], source: StateNode, edge: Edge
) -> str:
    """The DOT edge of a transition of ``node`` from its child ``source``."""
    attrs = [f"label={_q(edge.outcome)}"]
    if source.is_container:
        tail = _outcome_id(source, edge.outcome)
        if edge.outcome not in source.outcomes:
            tail = _entry(source)
            attrs.append(f"ltail={_q('cluster_' + source.path)}")
    else:
        tail = source.path
    if edge.terminal:
        head = _outcome_id(node, edge.target)
    else:
        target = by_label[edge.target]
        head = _entry(target)
        if target.is_container:
            attrs.append(f"lhead={_q('cluster_' + target.path)}")
    return f"  {_q(tail)} -> {_q(head)} [{', '.join(attrs)}];"


def _mid(path: str) -> str:
    return "s_" + re.sub(r"[^A-Za-z0-9_]", "_", path.strip("/")) if path.strip("/") else "s_root"


def to_mermaid(root: StateNode, active: Collection[str] = ()) -> str:
    """Mermaid ``stateDiagram-v2`` text for ``root``; ``active`` paths get a class."""
    active_set = set(active)
    lines = ["stateDiagram-v2"]
    classes: list[str] = []

    def emit(node: StateNode, depth: int) -> None:
        pad = "    " * depth
        nid = _mid(node.path)
        if node.path in active_set:
            classes.append(nid)
        if not node.is_container:
            lines.append(f'{pad}state "{node.label}" as {nid}')
            return
        lines.append(f'{pad}state "{node.label} ({node.type})" as {nid} {{')
        for child in node.children:
            emit(child, depth + 1)
        for outcome in node.outcomes:
            lines.append(f'{pad}    state "{outcome}" as {_mid(node.path)}__o_{_safe(outcome)}')
            classes_outcome.append(f"{_mid(node.path)}__o_{_safe(outcome)}")
        for initial in node.initial_states:
            lines.append(f"{pad}    [*] --> {_mid(node.path + '/' + initial)}")
        by_label = {c.label: c for c in node.children}
        for edge in node.edges:
            source = by_label.get(edge.source)
            if source is None:
                continue
            tail = _mid(source.path)
            if source.is_container and edge.outcome in source.outcomes:
                tail = f"{_mid(source.path)}__o_{_safe(edge.outcome)}"
            head = (
                f"{nid}__o_{_safe(edge.target)}"
                if edge.terminal
                else _mid(by_label[edge.target].path)
            )
            lines.append(f"{pad}    {tail} --> {head} : {edge.outcome}")
        lines.append(f"{pad}}}")

    classes_outcome: list[str] = []
    emit(root, 1)
    lines.append("    classDef outcome fill:#e0e0e0,stroke:#9e9e9e,font-size:10px")
    lines.append(f"    classDef active fill:{_ACTIVE},stroke:{_ACTIVE_STROKE},stroke-width:2px")
    for oid in classes_outcome:
        lines.append(f"    class {oid} outcome")
    for aid in classes:
        lines.append(f"    class {aid} active")
    return "\n".join(lines) + "\n"


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", text)


def to_svg(
    root: StateNode,
    active: Collection[str] = (),
    *,
    collapsed: Collection[str] = (),
    outcomes: Mapping[str, str] | None = None,
    preempt: Collection[str] = (),
    title: str | None = None,
) -> str:
    """Standalone SVG of ``root`` (our own layout, the live viewer's drawing).

    ``active`` paths are filled yellow, ``collapsed`` container paths drawn as one
    box, ``outcomes`` (path -> last outcome) written under the labels and ``preempt``
    paths marked "preempt requested". No Graphviz needed.
    """
    from smach.introspection.svg import render_svg

    return render_svg(
        root,
        collapsed=collapsed,
        active=active,
        outcomes=outcomes,
        preempt=preempt,
        title=title,
    )
