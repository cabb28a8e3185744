"""Exceptions raised by plan_bridge.

Expected planning outcomes (no plan, timeout, unsupported problem) are *results*
(:class:`plan_bridge.planning.planner.PlanResult`), not exceptions. Exceptions are for bad
input (a PDDL file that cannot be read, an unknown planner name, a fact that names
an unknown object) and broken infrastructure (the planner worker cannot start).

Every exception carries structured fields (path, line, column, ...) so callers can
render them, and a ``str()`` that is a complete, one-paragraph message for a user.
Constructors never log: callers decide what to do with the error.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TypedDict, Unpack

__all__ = [
    "FactError",
    "PddlError",
    "PddlPlace",
    "PlanBridgeError",
    "PlannerNotFoundError",
    "Terminated",
    "UnsupportedFeatureError",
    "WorkerError",
]


class PlanBridgeError(Exception):
    """Base class of every exception raised by plan_bridge."""


class Terminated(KeyboardInterrupt):
    """Raised in the main thread when the process gets SIGTERM (see :func:`plan_bridge.cli.main`).

    A :class:`KeyboardInterrupt`, so a termination takes the path of Ctrl-C: the
    journal is flushed and marked interrupted (a resume continues it), the viewer,
    the operator console and the planner workers are stopped.
    """


class PddlError(PlanBridgeError):
    """A PDDL input that cannot be loaded.

    ``str()`` reads like a compiler diagnostic::

        domain.pddl:12:15: unsupported PDDL construct `(either ...)` ...
            (in ?x - (either storearea crate) ?p - place)
                     ^
        allowed: ...
    """

    def __init__(
        self,
        explanation: str,
        *,
        path: str | Path | None = None,
        line: int | None = None,
        column: int | None = None,
        excerpt: str = "",
        hint: str = "",
    ) -> None:
        self.explanation = explanation
        self.path = str(path) if path is not None else None
        self.line = line
        self.column = column
        self.excerpt = excerpt
        self.hint = hint
        super().__init__(self._render())

    @property
    def location(self) -> str:
        """``path:line:column`` (as much of it as is known)."""
        parts = [self.path or "<pddl>"]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)

    def _render(self) -> str:
        text = f"{self.location}: {self.explanation}"
        if self.excerpt:
            text += "\n" + "\n".join("    " + row for row in self.excerpt.splitlines())
        if self.hint:
            text += "\n" + self.hint
        return text

    def __reduce__(self) -> tuple[object, ...]:
        # Keyword-only constructor: rebuild explicitly so errors survive pickling
        # (multiprocessing users, pytest-xdist).
        return (
            _rebuild,
            (
                type(self),
                self.explanation,
                {
                    "path": self.path,
                    "line": self.line,
                    "column": self.column,
                    "excerpt": self.excerpt,
                    "hint": self.hint,
                    **self._extra_state(),
                },
            ),
        )

    def _extra_state(self) -> dict[str, object]:
        return {}


class PddlPlace(TypedDict, total=False):
    """The keywords of :class:`PddlError` that say where, as its subclasses take them."""

    path: str | Path | None
    line: int | None
    column: int | None
    excerpt: str
    hint: str


class UnsupportedFeatureError(PddlError):
    """A PDDL feature the parser or the installed engines cannot handle.

    ``feature`` names the feature (``"either-types"``, ``":durative-actions"``);
    ``supporting_engines`` lists the installed engines that would handle it
    (empty when none does).
    """

    def __init__(
        self,
        explanation: str,
        *,
        feature: str,
        supporting_engines: Sequence[str] = (),
        **place: Unpack[PddlPlace],
    ) -> None:
        self.feature = feature
        self.supporting_engines = tuple(supporting_engines)
        super().__init__(explanation, **place)

    def _extra_state(self) -> dict[str, object]:
        return {"feature": self.feature, "supporting_engines": self.supporting_engines}


def _rebuild(cls: type[PddlError], explanation: str, state: dict[str, object]) -> PddlError:
    return cls(explanation, **state)  # type: ignore[arg-type]


class PlannerNotFoundError(PlanBridgeError, LookupError):
    """An engine name that is not an installed unified-planning one-shot planner."""

    def __init__(self, name: str, installed: Sequence[str]) -> None:
        self.name = name
        self.installed = tuple(installed)
        super().__init__(
            f"unknown planner {name!r}; use auto (the default choice by problem kind), "
            f"warm-gbfs (the in-worker search), or an installed engine: "
            f"{', '.join(self.installed) or 'none'}"
        )

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.name, self.installed))


class FactError(PlanBridgeError, ValueError):
    """A ground fact (e.g. in a replanning initial state) that does not fit the task."""


class WorkerError(PlanBridgeError):
    """The planner worker process could not be started or answered garbage."""
