"""Whether a journal tells what happened: the rules every journal holds, checked on a file.

:func:`journal_problems` lists every broken rule (an empty list: the journal is
faithful). The rules:

1. every event refers to a state path of the structure in force when it happened;
2. each machine's structure is written once, when it starts: every ``structure``
   record is followed by the ``container_started`` of its path, and a machine that
   starts again (the same plan machine after a retry of a step) writes none;
3. a checkpoint costs what changed, not the size of the state;
4. the replay at any position highlights exactly the states active then: the
   viewer's fold gives the active states of an independent fold of the events, and
   each of them is a node of the structure it draws.
"""

from __future__ import annotations

import json
import os
from typing import Any

from smach.introspection.compact import structure_of
from smach.introspection.journal import read_journal, read_states
from smach.introspection.model import History, graft

__all__ = ["journal_problems"]

MAX_PROBLEMS = 20

EVENT_KINDS = {
    "container_started",
    "state_entered",
    "state_exited",
    "transition",
    "container_terminated",
    "preempt_requested",
    "preempt_serviced",
    "userdata_written",
    "error",
}


def _paths(tree: dict[str, Any] | None) -> set[str]:
    found: set[str] = set()
    stack = [tree] if tree else []
    while stack:
        node = stack.pop()
        found.add(node["path"])
        stack.extend(node.get("children", ()))
    return found


def _independent_active(active: set[str], record: dict[str, Any], root: str) -> None:
    kind, path = record["kind"], record.get("path", "")
    if kind == "container_started" and path == root:
        active.clear()  # a new run of the root (a resume): the old one is over
    if kind in ("container_started", "state_entered"):
        active.add(path)
    elif kind in ("state_exited", "container_terminated", "error"):
        for p in [p for p in active if p == path or p.startswith(path + "/")]:
            active.discard(p)
    elif kind == "structure" and path:
        for p in [p for p in active if p.startswith(path + "/")]:
            active.discard(p)


def journal_problems(path: str | os.PathLike[str], *, every: int = 1) -> list[str]:
    """Every broken rule of the journal at ``path`` (at most :data:`MAX_PROBLEMS`).

    ``every``: check the replay after every ``every`` th record (1: after each).
    """
    problems: list[str] = []
    header, records = read_journal(path)
    tree = header.get("structure")
    in_force = _paths(tree)
    for n, record in enumerate(records, 1):
        kind = record.get("kind")
        if kind == "structure":
            tree = graft(tree, structure_of(record) or {}, record.get("path", ""))
            in_force = _paths(tree)
            started = next(
                (
                    r
                    for r in records[n:]
                    if r.get("kind") == "container_started" and r.get("path") == record.get("path")
                ),
                None,
            )
            if "path" not in record:
                problems.append(
                    f"record {n}: a structure of the whole tree, read when a new path was met "
                    f"(an older journal): it may show a later machine than the one that ran"
                )
            elif started is None or started.get("time") != record.get("time"):
                problems.append(
                    f"record {n}: the structure of {record.get('path')} was not written "
                    f"when it started"
                )
        elif kind in EVENT_KINDS and record.get("path") not in in_force:
            problems.append(
                f"record {n} ({kind}) is about {record.get('path')}, which the structure "
                f"in force does not have"
            )
    try:
        read_states(records, "checkpoint")
    except (ValueError, TypeError, KeyError, IndexError) as exc:
        problems.append(f"its checkpoints cannot be read back: {exc}")
    raw = [r for r in records if r.get("kind") == "checkpoint"]
    changes = [len(json.dumps(r)) for r in raw if "change" in r]
    wholes = [len(json.dumps(r)) for r in raw if "whole" in r]
    if changes and wholes and max(changes) >= max(wholes):
        problems.append("a checkpoint change is as large as a whole checkpoint")
    history = History(header, limit=len(records) + 1)
    first: dict[str, Any] = (
        header.get("structure")
        or next((structure_of(r) for r in records if r.get("kind") == "structure"), None)
        or {}
    )
    root = str(first.get("path", "/ROOT"))
    active: set[str] = set()
    for n, record in enumerate(records, 1):
        history.add(record)
        _independent_active(active, record, root)
        if n % every and n != len(records):
            continue
        view = history.view_at(n)
        if set(view.active) != active:
            problems.append(
                f"replay after record {n}: shows {sorted(view.active)}, active were "
                f"{sorted(active)}"
            )
        missing = set(view.active) - _paths(view.structure)
        if missing:
            problems.append(f"replay after record {n}: active but not drawn: {sorted(missing)}")
        if len(problems) >= MAX_PROBLEMS:
            break
    return problems[:MAX_PROBLEMS]
