"""Which structure a journal's events refer to: each machine's tree, written once, when it starts.

A replay draws the tree the events are about. Trees change while they run: an
executive compiles a new plan machine after every replan and puts it where the
last one was (``/ROOT/PLAN``). So the journal writes a ``structure`` record for
a container when an object it has not written yet *starts* at a path, before that
``container_started`` line:

    {"kind": "structure", "path": "/ROOT/PLAN", "time": ..., "structure": {...}}

``structure`` is the tree of that container only (the header holds the whole tree
at the start); a reader puts it in place of what was at ``path`` (see
:func:`smach.introspection.model.graft`). Containers inside it (the skills of a plan)
are part of it, so their own starts write nothing.

The tree must be read in the thread that starts the container, not later by the
journal's writer (by then the next plan may be in place: a replay would draw
steps that had not run yet and miss the one that ran). :class:`MachineTracker` is
the journal's capture function: for a ``container_started`` capture it finds the
container by its path and, if it is new, queues a
:class:`~smach.introspection.journal_lines.StructureItem` first; every capture is
then queued as it is. The check costs one dictionary lookup per container start.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from typing import Any

from smach.introspection.events import Capture, ContainerStarted
from smach.introspection.journal_lines import StructureItem
from smach.introspection.structure import StateNode, snapshot
from smach.state import State

__all__ = ["MachineTracker", "containers_below", "resolve"]


def resolve(root: State, path: str) -> State | None:
    """The state at ``path`` in the tree of ``root`` now (None if there is none)."""
    from smach.container import Container

    base = root.path or "/ROOT"
    if path == base:
        return root
    if not path.startswith(base + "/"):
        return None
    state: State = root
    for label in path[len(base) + 1 :].split("/"):
        if not isinstance(state, Container):
            return None
        child = state.get_children().get(label)
        if child is None:
            return None
        state = child
    return state


def containers_below(state: State, path: str) -> Iterator[tuple[str, State]]:
    """``(path, container)`` of ``state`` (if it is one) and of every container below it."""
    from smach.container import Container

    stack: list[tuple[str, State]] = [(path, state)]
    while stack:
        here, s = stack.pop()
        if isinstance(s, Container):
            yield here, s
            stack.extend((f"{here}/{label}", child) for label, child in s.get_children().items())


def read_tree(state: State) -> StateNode | None:
    """A snapshot of ``state``, read again if another thread changed it meanwhile."""
    for _ in range(3):
        try:
            return snapshot(state)
        except RuntimeError:  # a dictionary changed size while we read it
            continue
    return None


class MachineTracker:
    """The capture function of a journal: queue a new machine's tree before its start.

    ``in_force`` maps the path of every container whose structure the journal has
    (header or ``structure`` records) to the object it was read from.
    """

    def __init__(self, root: State, queue: Callable[[Any], object], *, written: bool) -> None:
        self.root = root
        self.queue = queue
        self.lock = threading.Lock()
        base = root.path or "/ROOT"
        # written: the header holds the tree as it is now.
        self.in_force: dict[str, State] = dict(containers_below(root, base)) if written else {}
        self.structures = 0
        """How many structure records were queued."""

    def __call__(self, capture: Capture) -> None:
        if capture[0] is ContainerStarted:
            self._started(capture)
        self.queue(capture)

    def _started(self, capture: Capture) -> None:
        path = capture[1]
        container = resolve(self.root, path)
        if container is None or self.in_force.get(path) is container:
            return
        tree = read_tree(container)
        if tree is None:
            return
        with self.lock:
            prefix = path + "/"
            for known in [p for p in self.in_force if p.startswith(prefix)]:
                del self.in_force[known]
            self.in_force.update(containers_below(container, path))
            self.structures += 1
            self.queue(StructureItem(path, capture[2], tree))
