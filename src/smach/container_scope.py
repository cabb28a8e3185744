"""Scoping: how a container copies its declared keys in from and out to its parent.

:class:`ContainerScope` is the part of :class:`~smach.container.Container` that copies
the declared input keys from the parent's userdata (or the view the parent gave it)
into the container's own userdata when a run starts, and the declared output keys
back when it ends.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from smach.log import loggers
from smach.user_data import MISSING, Remapper, UserData

__all__ = ["ContainerScope", "CopyPlan"]

CopyPlan = tuple[UserData, dict[str, Any] | None, tuple[tuple[str, str | None], ...]]
"""How a container copies keys from or to a parent userdata: see ContainerScope."""


class ContainerScope:
    """Copying declared keys between scopes (mixed into ``Container``)."""

    _path: str
    _userdata: UserData
    _input_keys: dict[str, None]
    _output_keys: dict[str, None]
    _copies_in: bool | CopyPlan
    _copies_out: bool | CopyPlan

    # Copying keys between scopes. A container remembers, in ``_copies_in`` and
    # ``_copies_out`` (True/False until then), how to copy to and from the parent
    # userdata (or view) it was last given: ``(parent_ud, dict, ((key, target), ...))``,
    # with its declared keys and remapping applied (target None: the view does not
    # declare the key). A run with the same parent then costs a dict lookup per key.
    def _plan_copies(self, parent_ud: UserData) -> None:
        """Plan the copies to and from ``parent_ud`` now (the view a parent built for
        this container while compiling), so that the first run finds them made."""
        if self._input_keys:
            self._copies_in = _copy_plan(parent_ud, self._input_keys, inputs=True)
        if self._output_keys:
            self._copies_out = _copy_plan(parent_ud, self._output_keys, inputs=False)

    def _copy_input_keys(self, parent_ud: UserData | None) -> None:
        if parent_ud is None:
            return
        plan = self._copies_in
        if not isinstance(plan, tuple) or plan[0] is not parent_ud:
            plan = self._copies_in = _copy_plan(parent_ud, self._input_keys, inputs=True)
        data, pairs = plan[1], plan[2]
        local = self._userdata._data
        for key, target in pairs:
            if target is None:
                value = MISSING
            elif data is None:  # a view of a view: through its checks
                value = parent_ud._take(key)
            else:
                value = data.get(target, MISSING)
            if value is not MISSING:
                local[key] = value
            elif key not in local:
                loggers.logwarn(
                    f"{self._path}: input key {key!r} is not available in the parent userdata"
                )

    def _copy_output_keys(self, parent_ud: UserData | None) -> None:
        if parent_ud is None:
            return
        plan = self._copies_out
        if not isinstance(plan, tuple) or plan[0] is not parent_ud:
            plan = self._copies_out = _copy_plan(parent_ud, self._output_keys, inputs=False)
        data, pairs = plan[1], plan[2]
        local = self._userdata._data
        view = parent_ud if isinstance(parent_ud, Remapper) else None  # (writes reported)
        for key, target in pairs:
            if key not in local:
                continue
            if target is None or data is None:
                parent_ud[key] = local[key]  # (through the view: its checks, its events)
                continue
            data[target] = value = local[key]
            if view is not None and view._bus is not None and view._bus.listeners:
                view._written(view._bus, target, value)


def _copy_plan(parent_ud: UserData, keys: Iterable[str], *, inputs: bool) -> CopyPlan:
    """How a container copies ``keys`` from (``inputs``) or to ``parent_ud``: the dict
    to use directly (None: go through the view) and each key's name in it."""
    data: dict[str, Any] | None = None
    pairs: tuple[tuple[str, str | None], ...]
    if type(parent_ud) is UserData:
        data, pairs = parent_ud._data, tuple((key, key) for key in keys)
    elif isinstance(parent_ud, Remapper) and parent_ud._d is not None:
        declared = parent_ud._in if inputs else parent_ud._out
        remap = parent_ud._remap
        data = parent_ud._d
        pairs = tuple((key, remap.get(key, key) if key in declared else None) for key in keys)
    else:
        pairs = tuple((key, key) for key in keys)
    # Equal pairs are shared (nested machines passing a key down have the same ones):
    # a fresh tree's first run then finds them in the cache.
    return parent_ud, data, _PAIRS.setdefault(pairs, pairs)


_PAIRS: dict[tuple[tuple[str, str | None], ...], tuple[tuple[str, str | None], ...]] = {}
