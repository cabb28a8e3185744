"""Consistency checks of a container and of the tree below it.

:class:`ContainerChecks` is the part of :class:`~smach.container.Container` that
checks before a run (or at ``close()``): each container reports its own problems
(``consistency_problems``), a tree is checked once, and every problem is reported
together.
"""

from __future__ import annotations

from smach.exceptions import InvalidTransitionError, SmachError
from smach.state import State

__all__ = ["ContainerChecks"]


class ContainerChecks:
    """Consistency checks (mixed into ``Container``)."""

    _path: str
    # This container alone checked since its last change; it and everything below.
    _consistent: bool
    _subtree_ok: bool

    def get_children(self) -> dict[str, State]:
        raise NotImplementedError

    def check_consistency(self) -> None:
        """Raise :class:`InvalidTransitionError` listing every problem of this container."""
        self._raise_problems(self.consistency_problems())

    def consistency_problems(self) -> list[str]:
        """Every reason this container (alone) cannot run, one line each."""
        raise NotImplementedError

    def _raise_problems(self, problems: list[str]) -> None:
        if problems:
            count = f"{len(problems)} problem{'s' if len(problems) > 1 else ''}"
            raise InvalidTransitionError(
                f"{_KIND_NAMES.get(type(self).__name__, type(self).__name__)} {self._path} is "
                f"inconsistent ({count}):\n  " + "\n  ".join(problems)
            )

    def _own_problems(self) -> list[str]:
        try:
            return self.consistency_problems()
        except NotImplementedError:
            try:
                self.check_consistency()
            except SmachError as exc:
                return [f"{self._path}: {exc}"]
            return []

    def subtree_problems(self) -> list[str]:
        """The consistency problems of this container and of every container below it."""
        problems: list[str] = []
        stack: list[object] = [self]
        while stack:
            node = stack.pop()
            if isinstance(node, ContainerChecks):
                problems.extend(node._own_problems())
                stack.extend(reversed(list(node.get_children().values())))
        return problems

    def _check_before_run(self) -> None:
        """Refuse to run if anything in the tree below is inconsistent (all problems at once).

        A container checked since its last change is not checked again, and a subtree
        found consistent is marked so: a tree is checked once, not once per level.
        """
        problems: list[str] = []
        checked: list[ContainerChecks] = []
        stack: list[object] = [self]
        while stack:
            node = stack.pop()
            if not isinstance(node, ContainerChecks) or node._subtree_ok:
                continue
            checked.append(node)
            if not node._consistent:
                own = node._own_problems()
                problems.extend(own)
                node._consistent = not own
            stack.extend(reversed(list(node.get_children().values())))
        self._raise_problems(problems)
        for done in checked:
            done._subtree_ok = True


_KIND_NAMES = {
    "StateMachine": "state machine",
    "Concurrence": "concurrence",
    "Iterator": "iterator",
}
