"""The exceptions of smach.

Four public error classes are kept from the original SMACH, all subclasses of
:class:`SmachError`. Unlike the original, constructing an exception never logs:
an error is reported once, by whoever handles it.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "InvalidConstructionError",
    "InvalidOutcomeError",
    "InvalidStateError",
    "InvalidTransitionError",
    "InvalidUserCodeError",
    "MissingExtraError",
    "NoContainerOpenError",
    "SmachError",
    "UndeclaredKeyError",
    "UserDataKeyError",
]


class MissingExtraError(ModuleNotFoundError):
    """An optional part of smach-planner whose packages are not installed (an extra
    such as ``ros``); the message names what is missing and the pip command. A
    ``ModuleNotFoundError``, so ``pytest.importorskip`` and code probing for the
    extra treat it as the missing module it is."""


class SmachError(Exception):
    """Base class of every error raised by smach."""

    def __init__(self, message: str = "") -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return self.message


class InvalidStateError(SmachError):
    """A state or container was used in a way its interface does not allow."""


class InvalidTransitionError(SmachError):
    """A transition names an unknown target or an outcome that does not exist."""


class InvalidUserCodeError(SmachError):
    """User code (a state's execute, a callback) misbehaved or raised."""


class InvalidConstructionError(SmachError):
    """A construction call was made with no container open."""


class InvalidOutcomeError(InvalidUserCodeError, InvalidTransitionError):
    """A state returned something that is not one of its registered outcomes.

    Both an :class:`InvalidUserCodeError` and, as in the original SMACH, an
    :class:`InvalidTransitionError`.
    """


class NoContainerOpenError(InvalidConstructionError, InvalidStateError):
    """A class-level construction call was made with no container open.

    Both an :class:`InvalidConstructionError` and, as in the original SMACH, an
    :class:`InvalidStateError`.
    """


class UserDataKeyError(SmachError, KeyError, AttributeError):
    """A userdata key is missing.

    It is both a ``KeyError`` (for ``ud['k']``) and an ``AttributeError`` (so that
    ``hasattr(ud, 'k')`` and ``getattr(ud, 'k', default)`` work on ``ud.k``).
    """

    def __init__(
        self, key: str, available: Iterable[object], remapped_to: str | None = None
    ) -> None:
        keys = sorted(str(k) for k in available)
        listed = ", ".join(repr(k) for k in keys) if keys else "none"
        where = f" (remapped to {remapped_to!r})" if remapped_to and remapped_to != key else ""
        super().__init__(f"userdata key {key!r}{where} is not available; available keys: {listed}")
        self.key = key

    def __str__(self) -> str:  # KeyError would otherwise repr() the message
        return self.message


class UndeclaredKeyError(InvalidUserCodeError, KeyError, AttributeError):
    """A state read a userdata key it did not declare as an input key."""

    def __str__(self) -> str:
        return self.message
