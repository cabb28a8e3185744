"""Structure snapshots: a tree of states as plain, immutable data.

A snapshot is what viewers, exporters and the journal header need: paths, types,
outcomes, keys, children, edges and initial states. It reads the tree through the
Container interface only, so it works for user-defined containers too.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from smach.state import State

__all__ = ["Edge", "StateNode", "snapshot"]


@dataclass(frozen=True)
class Edge:
    """``source`` returning ``outcome`` leads to ``target``.

    ``target`` is a sibling label, or a container outcome when ``terminal`` is true.
    """

    source: str
    outcome: str
    target: str
    terminal: bool

    def to_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "outcome": self.outcome,
            "target": self.target,
            "terminal": self.terminal,
        }


@dataclass(frozen=True)
class StateNode:
    """One state of a tree; containers have children and edges."""

    path: str
    label: str
    type: str
    outcomes: tuple[str, ...]
    input_keys: tuple[str, ...]
    output_keys: tuple[str, ...]
    is_container: bool = False
    children: tuple[StateNode, ...] = ()
    edges: tuple[Edge, ...] = ()
    initial_states: tuple[str, ...] = ()
    extra: dict[str, Any] = field(default_factory=dict)

    def walk(self) -> Iterator[StateNode]:
        """This node and every node below it, depth first."""
        yield self
        for child in self.children:
            yield from child.walk()

    def find(self, path: str) -> StateNode | None:
        return next((n for n in self.walk() if n.path == path), None)

    def to_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "path": self.path,
            "label": self.label,
            "type": self.type,
            "outcomes": list(self.outcomes),
            "input_keys": list(self.input_keys),
            "output_keys": list(self.output_keys),
            "is_container": self.is_container,
        }
        if self.is_container:
            data["children"] = [c.to_dict() for c in self.children]
            data["edges"] = [e.to_dict() for e in self.edges]
            data["initial_states"] = list(self.initial_states)
        if self.extra:
            data["extra"] = dict(self.extra)
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StateNode:
        """Rebuild a snapshot from :meth:`to_dict` output (e.g. a journal header)."""
        return cls(
            path=str(data["path"]),
            label=str(data["label"]),
            type=str(data["type"]),
            outcomes=tuple(data.get("outcomes", ())),
            input_keys=tuple(data.get("input_keys", ())),
            output_keys=tuple(data.get("output_keys", ())),
            is_container=bool(data.get("is_container", False)),
            children=tuple(cls.from_dict(c) for c in data.get("children", ())),
            edges=tuple(
                Edge(str(e["source"]), str(e["outcome"]), str(e["target"]), bool(e["terminal"]))
                for e in data.get("edges", ())
            ),
            initial_states=tuple(data.get("initial_states", ())),
            extra=dict(data.get("extra", {})),
        )


def snapshot(state: State, label: str | None = None) -> StateNode:
    """Take a snapshot of ``state`` and everything below it."""
    from smach.container import Container

    return _snapshot(state, label, Container)


def _snapshot(state: State, label: str | None, container: type[Any]) -> StateNode:
    path = state.path or "/" + (label or "ROOT")
    name = label or path.rsplit("/", 1)[-1] or "ROOT"
    kind = type(state).__name__
    outcomes = state.get_registered_outcomes()
    input_keys = state.get_registered_input_keys()
    output_keys = state.get_registered_output_keys()
    if not isinstance(state, container):
        return StateNode(path, name, kind, outcomes, input_keys, output_keys)
    children = state.get_children()
    child_nodes = tuple(
        [_snapshot(child, child_label, container) for child_label, child in children.items()]
    )
    edges: list[Edge] = []
    for outcome, source, target in state.get_internal_edges():
        if target is None or target == "":
            edges.append(Edge(source, outcome, outcome, True))
        elif target in children:
            edges.append(Edge(source, outcome, target, False))
        else:
            edges.append(Edge(source, outcome, target, True))
    return StateNode(
        path,
        name,
        kind,
        outcomes,
        input_keys,
        output_keys,
        is_container=True,
        children=child_nodes,
        edges=tuple(edges),
        initial_states=tuple(state.get_initial_states()),
    )
