"""Static exports of a structure, or of a journal at a given moment.

``export_journal("run.jsonl", "svg", at=2.5)`` draws the machine as it was 2.5 s
after the first event: active states coloured, last outcomes written, a pending
preempt marked. DOT and Mermaid get the active states; SVG needs no Graphviz.
"""

from __future__ import annotations

import os
from typing import Any

from smach.introspection.journal import read_journal
from smach.introspection.model import ViewModel, active_at
from smach.introspection.render import to_dot, to_mermaid
from smach.introspection.structure import StateNode

__all__ = ["FORMATS", "export_journal", "export_view"]

FORMATS = ("dot", "mermaid", "svg")


def export_view(model: ViewModel, fmt: str, *, title: str | None = None) -> str:
    """``model`` (a folded view) as DOT, Mermaid or SVG text."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; formats: {', '.join(FORMATS)}")
    if not model.structure:
        raise ValueError("no structure to export (the journal has no structure snapshot)")
    root = StateNode.from_dict(model.structure)
    active = list(model.active)
    if fmt == "dot":
        return to_dot(root, active)
    if fmt == "mermaid":
        return to_mermaid(root, active)
    from smach.introspection.svg import render_svg

    reached: list[str] = []
    if model.root_outcome and not model.running:
        reached.append(f"{root.path}:{model.root_outcome}")
    return render_svg(
        root,
        active=active,
        outcomes=model.outcomes,
        preempt=[p for p, s in model.preempt.items() if s == "requested"],
        errors=list(model.error_paths),
        taken={k: (v[0], v[1]) for k, v in model.last_edges.items()},
        reached=reached,
        title=title,
    )


def export_journal(
    path: str | os.PathLike[str],
    fmt: str,
    *,
    at: float | None = None,
    event: int | None = None,
) -> str:
    """The journal at ``path`` drawn ``at`` seconds in, after ``event`` events, or at its end."""
    header, records = read_journal(path)
    model = active_at(header, records, at=at, event=event)
    return export_view(model, fmt, title=_title(header, path))


def _title(header: dict[str, Any], path: str | os.PathLike[str]) -> str:
    return str(header.get("title") or os.path.basename(os.fspath(path)))
