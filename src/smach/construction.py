"""Construction of containers: the per-thread stack of open containers and the
methods that, called on the class (``StateMachine.add(...)``), act on the open one."""

from __future__ import annotations

import functools
import threading
import types
from collections.abc import Callable
from typing import Any, Concatenate, Generic, ParamSpec, TypeVar

from smach.state import State

__all__ = ["construction_method"]

C = TypeVar("C", bound=State)
P = ParamSpec("P")
R = TypeVar("R")


class _ConstructionStack(threading.local):
    def __init__(self) -> None:
        # The open containers (smach.container.Container), innermost last.
        self.stack: list[Any] = []


_construction = _ConstructionStack()


class construction_method(Generic[C, P, R]):  # noqa: N801  (reads like a decorator)
    """A method that, called on the class, acts on the currently open container.

    ``StateMachine.add(...)`` inside ``with sm:`` adds to ``sm``; ``sm.add(...)`` adds
    to ``sm`` whether or not it is open.
    """

    def __init__(self, fn: Callable[Concatenate[C, P], R]) -> None:
        self._fn = fn
        functools.update_wrapper(self, fn)  # type: ignore[arg-type]
        # The class-level callable of each owner class, built once (building one per
        # call would cost a functools.wraps per added state).
        self._on_class: dict[type[C], Callable[P, R]] = {}

    def __get__(self, obj: C | None, objtype: type[C] | None = None) -> Callable[P, R]:
        fn = self._fn
        if obj is not None:
            return types.MethodType(fn, obj)
        assert objtype is not None
        on_class = self._on_class.get(objtype)
        if on_class is None:
            owner: Any = objtype  # a Container class: it has _currently_opened_container

            @functools.wraps(fn)
            def on_open_container(*args: P.args, **kwargs: P.kwargs) -> R:
                return fn(owner._currently_opened_container(), *args, **kwargs)

            on_class = self._on_class[objtype] = on_open_container
        return on_class


def _label_problem(label: object) -> str | None:
    if not isinstance(label, str) or not label:
        return f"a state label must be a non-empty string, got {label!r}"
    if "/" in label:
        return f"state label {label!r} must not contain '/' (it separates path segments)"
    return None
