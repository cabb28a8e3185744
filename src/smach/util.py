"""Shutdown hook and callback interfaces (``smach.util`` in the original)."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from typing import Any

from smach.exceptions import InvalidStateError

__all__ = [
    "CBInterface",
    "ShutdownCheck",
    "cb_interface",
    "has_smach_interface",
    "is_shutdown",
    "set_shutdown_check",
    "shutdown",
]


def is_shutdown() -> bool:
    """Default shutdown check: never shut down."""
    return False


class ShutdownCheck:
    """The shutdown check containers call between states, replaceable at run time
    (``smach.is_shutdown`` reads and sets :attr:`check`)."""

    __slots__ = ("check",)

    def __init__(self) -> None:
        self.check: Callable[[], bool] = is_shutdown


#: The shutdown check of this process; :func:`is_shutdown` (never) by default.
shutdown = ShutdownCheck()


def set_shutdown_check(cb: Callable[[], bool]) -> None:
    """Install ``cb`` as ``smach.is_shutdown`` (checked by containers between states)."""
    shutdown.check = cb


def key_list(value: Iterable[str] | None, what: str) -> list[str]:
    """Normalise an outcomes/keys argument into a list of strings.

    A bare string is refused: the original iterated it character by character, which
    was never what the caller meant.
    """
    if value is None:
        return []
    if isinstance(value, str):
        raise InvalidStateError(
            f"{what} must be a list of strings, got the string {value!r}; did you mean [{value!r}]?"
        )
    items = list(value)
    for item in items:
        if not isinstance(item, str):
            raise InvalidStateError(
                f"{what} must contain strings, got {item!r} ({type(item).__name__})"
            )
    return items


class CBInterface:
    """A callable annotated with the outcomes and userdata keys it uses.

    Created by :func:`cb_interface`. It works on plain functions and on methods
    (it implements the descriptor protocol, so ``self`` is bound as usual).
    """

    def __init__(
        self,
        cb: Callable[..., Any],
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        io_keys: Iterable[str] | None = None,
    ) -> None:
        io = key_list(io_keys, "io_keys")
        self._cb = cb
        self._outcomes = dict.fromkeys(key_list(outcomes, "outcomes"))
        self._input_keys = dict.fromkeys(key_list(input_keys, "input_keys") + io)
        self._output_keys = dict.fromkeys(key_list(output_keys, "output_keys") + io)
        functools.update_wrapper(self, cb)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._cb(*args, **kwargs)

    def __get__(self, obj: object, objtype: type | None = None) -> CBInterface:
        if obj is None:
            return self
        bound = CBInterface(self._cb.__get__(obj, objtype))
        bound._outcomes = self._outcomes
        bound._input_keys = self._input_keys
        bound._output_keys = self._output_keys
        return bound

    def get_registered_outcomes(self) -> tuple[str, ...]:
        return tuple(self._outcomes)

    def get_registered_input_keys(self) -> tuple[str, ...]:
        return tuple(self._input_keys)

    def get_registered_output_keys(self) -> tuple[str, ...]:
        return tuple(self._output_keys)


def cb_interface(
    outcomes: Iterable[str] | None = None,
    input_keys: Iterable[str] | None = None,
    output_keys: Iterable[str] | None = None,
    io_keys: Iterable[str] | None = None,
) -> Callable[[Callable[..., Any]], CBInterface]:
    """Decorator declaring the outcomes and keys of a callback (for CBState and ROS states)."""

    def decorate(cb: Callable[..., Any]) -> CBInterface:
        return CBInterface(cb, outcomes, input_keys, output_keys, io_keys)

    return decorate


def has_smach_interface(obj: object) -> bool:
    """True if ``obj`` declares outcomes and keys the SMACH way."""
    return all(
        hasattr(obj, name)
        for name in (
            "get_registered_input_keys",
            "get_registered_output_keys",
            "get_registered_outcomes",
        )
    )
