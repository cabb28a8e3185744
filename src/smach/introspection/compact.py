"""A structure snapshot written small: repeated subtrees once, edges as runs, no paths.

A plan machine of 2000 steps is 2000 copies of a few step shapes chained by the same
edges; written as plain :meth:`StateNode.to_dict` data it is about 2 KB per step,
and an executive writes a new one after every retry or replan. :func:`compact`
writes it so that it costs a few dozen bytes per step; :func:`expand` gives the
plain data back:

* no ``path`` fields: a node's path is its parent's path, ``/`` and its label;
* a subtree seen before in the same record is ``{"label": ..., "like": id}``: a copy
  of the node that carried ``"id": id``, under another label;
* a container's edges are runs ``[outcome, target, terminal, first, last]`` over the
  indexes of its children: ``source`` is each child from ``first`` to ``last``;
  ``target`` is a label, or an int ``k`` for "the child ``k`` places further on"
  (a chain: ``["succeeded", 1, false, 0, 1998]``).

Each record is self-contained: no table is shared between records.
"""

from __future__ import annotations

import json
from typing import Any

__all__ = ["compact", "expand", "structure_of"]

_MIN_SHARED = 60
"""Subtrees whose compact text is shorter are not worth a reference."""


def compact(tree: dict[str, Any]) -> dict[str, Any]:
    """``tree`` (:meth:`StateNode.to_dict` data) in the compact form."""
    seen: dict[str, int] = {}
    return _compact(tree, seen)


def _compact(node: dict[str, Any], seen: dict[str, int]) -> dict[str, Any]:
    out = {k: v for k, v in node.items() if k not in ("path", "children", "edges")}
    if node.get("is_container"):
        children = node.get("children", [])
        out["children"] = [_compact_child(child, seen) for child in children]
        out["edges"] = _runs(node.get("edges", []), [c["label"] for c in children])
    return out


def _compact_child(node: dict[str, Any], seen: dict[str, int]) -> dict[str, Any]:
    key = json.dumps(_shape(node, root=True), sort_keys=True)
    known = seen.get(key)
    if known is not None:
        return {"label": node["label"], "like": known}
    body = _compact(node, seen)
    if len(key) < _MIN_SHARED:
        return body
    seen[key] = len(seen)
    return {**body, "id": seen[key]}


def _shape(node: dict[str, Any], root: bool = False) -> dict[str, Any]:
    """The node without its paths (and, for the root, its label): what copies share."""
    out = {k: v for k, v in node.items() if k not in ("path", "children")}
    if root:
        del out["label"]
    if "children" in node:
        out["children"] = [_shape(child) for child in node["children"]]
    return out


def _runs(edges: list[dict[str, Any]], labels: list[str]) -> list[list[Any]]:
    index = {label: i for i, label in enumerate(labels)}
    runs: list[list[Any]] = []
    open_runs: dict[tuple[Any, ...], list[Any]] = {}
    for edge in edges:
        source = index.get(edge["source"])
        if source is None:  # not a child: kept as it is
            runs.append([edge["outcome"], edge["target"], edge["terminal"], edge["source"]])
            continue
        target: Any = edge["target"]
        if not edge["terminal"] and target in index:
            target = index[target] - source
        key = (edge["outcome"], target, edge["terminal"])
        run = open_runs.get(key)
        if run is not None and run[4] == source - 1:
            run[4] = source
            continue
        run = [edge["outcome"], target, edge["terminal"], source, source]
        open_runs[key] = run
        runs.append(run)
    return runs


def expand(data: dict[str, Any], path: str) -> dict[str, Any]:
    """The plain data of a :func:`compact` tree whose root is at ``path``."""
    shared: dict[int, dict[str, Any]] = {}
    return _expand(data, path, shared)


def _expand(node: dict[str, Any], path: str, shared: dict[int, dict[str, Any]]) -> dict[str, Any]:
    if "like" in node:
        node = {**shared[int(node["like"])], "label": node["label"]}
    out: dict[str, Any] = {"path": path}
    out.update({k: v for k, v in node.items() if k not in ("children", "edges", "id", "like")})
    if "id" in node:
        shared[int(node["id"])] = {k: v for k, v in node.items() if k != "id"}
    if node.get("is_container"):
        children = node.get("children", [])
        expanded = [_expand(child, f"{path}/{child['label']}", shared) for child in children]
        labels = [child["label"] for child in expanded]
        out["children"] = expanded
        out["edges"] = _edges(node.get("edges", []), labels)
    return out


def _edges(runs: list[list[Any]], labels: list[str]) -> list[dict[str, Any]]:
    found: list[tuple[int, int, dict[str, Any]]] = []
    for order, run in enumerate(runs):
        if len(run) == 4:  # a source that is not a child
            outcome, target, terminal, source = run
            found.append((len(labels), order, _edge(source, outcome, target, terminal)))
            continue
        outcome, target, terminal, first, last = run
        for i in range(first, last + 1):
            to = labels[i + target] if type(target) is int else target
            found.append((i, order, _edge(labels[i], outcome, to, terminal)))
    found.sort(key=lambda item: (item[0], item[1]))
    return [edge for _, _, edge in found]


def _edge(source: str, outcome: str, target: str, terminal: bool) -> dict[str, Any]:
    return {"source": source, "outcome": outcome, "target": target, "terminal": terminal}


def structure_of(record: dict[str, Any]) -> dict[str, Any] | None:
    """The plain tree of a ``structure`` record (compact or not), or None."""
    tree = record.get("structure")
    if isinstance(tree, dict):
        return tree
    data = record.get("compact")
    if isinstance(data, dict):
        return expand(data, str(record.get("path", "")))
    return None
