"""Userdata: the scoped key/value store each container owns.

:class:`UserData` is a dictionary with attribute access. A child state never sees a
container's ``UserData`` directly but through a :class:`Remapper`, which enforces
the keys the state declared and translates state-local names to container names.
Values are shared by reference, never copied. Single reads and writes are atomic
(they are one dict operation under the GIL); the original's per-key locks added no
guarantee beyond that and are not reproduced.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Iterator, Mapping
from typing import Any, ClassVar

from smach.events import EventBus, UserdataWritten, stamp
from smach.exceptions import InvalidUserCodeError, UndeclaredKeyError, UserDataKeyError
from smach.summary import frozen

__all__ = ["MISSING", "Const", "Remapper", "UserData", "get_const", "make_remapper"]

MISSING: Any = object()
"""What :meth:`UserData._take` returns for a key that has no value."""
_MISSING = MISSING


class UserData:
    """A dictionary with attribute access: ``ud.x``, ``ud['x']``, ``'x' in ud``."""

    __slots__ = ("_data",)

    _data: dict[str, Any]

    def __init__(self, data: Mapping[str, Any] | None = None) -> None:
        object.__setattr__(self, "_data", dict(data) if data else {})

    # -- dictionary protocol -------------------------------------------------
    def __getattr__(self, name: str) -> Any:
        # Only called when normal lookup fails, i.e. for user keys.
        if name.startswith("__"):
            raise AttributeError(name)
        value = self._data.get(name, _MISSING)
        if value is _MISSING:
            raise UserDataKeyError(name, self._data)
        return value

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
        else:
            self._data[name] = value

    def __getitem__(self, key: str) -> Any:
        value = self._data.get(key, _MISSING)
        if value is _MISSING:
            raise UserDataKeyError(key, self._data)
        return value

    def __setitem__(self, key: str, value: Any) -> None:
        self._data[key] = value

    def __delitem__(self, key: str) -> None:
        if key not in self._data:
            raise UserDataKeyError(key, self._data)
        del self._data[key]

    def __contains__(self, key: object) -> bool:
        return key in self._data

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._data))

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._data!r})"

    def keys(self) -> list[str]:
        return list(self._data)

    def _take(self, key: str) -> Any:
        """The value of ``key`` as stored (:data:`MISSING` if none): for copying between
        scopes (a container's input keys), never wrapped read-only."""
        return self._data.get(key, MISSING)

    def update(self, other: UserData | Mapping[str, Any]) -> None:
        """Merge another userdata (or a mapping) into this one, overwriting."""
        if isinstance(other, UserData):
            for key in other:
                self[key] = other[key]
        else:
            for key, value in other.items():
                self[key] = value

    # -- kept from the original, unused by the library -------------------------
    def extract(self, keys: Iterable[str], remapping: Mapping[str, str]) -> UserData:
        ud = UserData()
        reverse = {v: k for k, v in remapping.items()}
        for k in keys:
            ud[reverse.get(k, k)] = copy.copy(self[k])
        return ud

    def merge(self, ud: UserData, keys: Iterable[str], remapping: Mapping[str, str]) -> None:
        for k in keys:
            self[remapping.get(k, k)] = copy.copy(ud[k])

    def __getstate__(self) -> dict[str, Any]:
        return self._data

    def __setstate__(self, state: dict[str, Any]) -> None:
        object.__setattr__(self, "_data", state)


_PLAIN = frozenset({int, float, str, bool, bytes, type(None), tuple, list, dict, set, frozenset})


class Const:
    """A read-only view of an object given to a state through an input-only key.

    Reading attributes works (and wraps nested objects again); setting or deleting an
    attribute raises :class:`InvalidUserCodeError`. Methods that mutate (``append``)
    pass through, as in the original.
    """

    __slots__ = ("_Const__obj",)

    def __init__(self, obj: Any) -> None:
        object.__setattr__(self, "_Const__obj", obj)

    def __getattr__(self, name: str) -> Any:
        return get_const(getattr(self.__obj, name))

    def __setattr__(self, name: str, value: Any) -> None:
        raise InvalidUserCodeError(
            f"cannot set attribute {name!r} of {type(self.__obj).__name__}: it was read through "
            "an input-only userdata key; declare the key as an output or io key to modify it"
        )

    def __delattr__(self, name: str) -> None:
        raise InvalidUserCodeError(
            f"cannot delete attribute {name!r}: the object was read through an input-only key"
        )

    def __getitem__(self, key: Any) -> Any:
        return get_const(self.__obj[key])

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Const):
            other = object.__getattribute__(other, "_Const__obj")
        return bool(self.__obj == other)

    def __hash__(self) -> int:
        return hash(self.__obj)

    def __repr__(self) -> str:
        return f"Const({self.__obj!r})"


def get_const(obj: Any) -> Any:
    """Wrap objects that have attributes of their own in :class:`Const`."""
    if type(obj) in _PLAIN or not hasattr(obj, "__dict__") or callable(obj):
        return obj
    return Const(obj)


class Remapper(UserData):
    """The view a state gets of its container's userdata.

    ``remapping`` maps state-local key -> container key. Reading a key that is not a
    declared input key, or writing one that is not a declared output key, raises
    :class:`InvalidUserCodeError` naming the state and its declared keys.

    ``path`` is the container's path and ``writer`` the state's label (for error
    messages, and for the ``userdata_written`` events that go to ``bus`` when it has
    listeners). ``owner`` (a container) is the older way to give both path and bus.
    """

    __slots__ = ("_bus", "_d", "_in", "_out", "_path", "_remap", "_rw", "_ud", "_writer")

    _ud: UserData
    _d: dict[str, Any] | None
    _in: frozenset[str]
    _out: frozenset[str]
    _rw: frozenset[str]
    _remap: dict[str, str]
    _path: str
    _bus: EventBus | None
    _writer: str
    #: Fast subclasses (make_remapper): declared output key -> container key.
    _writes: ClassVar[dict[str, str]] = {}

    def __init__(
        self,
        ud: UserData,
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        remapping: Mapping[str, str] | None = None,
        *,
        path: str = "",
        bus: EventBus | None = None,
        writer: str = "",
        owner: Any = None,
    ) -> None:
        set_ = object.__setattr__
        set_(self, "_ud", ud)
        # Over a plain UserData, read its dict directly; over another Remapper (a state
        # wrapping the view it was given), go through that view and its checks.
        set_(self, "_d", None if isinstance(ud, Remapper) else ud._data)
        set_(self, "_in", frozenset(input_keys))
        set_(self, "_out", frozenset(output_keys))
        set_(self, "_rw", self._in & self._out)
        set_(self, "_remap", dict(remapping) if remapping else {})
        set_(self, "_writer", writer)
        self._retarget(*_where(path, bus, owner))

    def _retarget(self, path: str, bus: EventBus | None) -> None:
        """Name the container (``path``) and the bus that writes are reported to.

        A container calls it on the views it built when it joins another tree.
        """
        object.__setattr__(self, "_path", path)
        object.__setattr__(self, "_bus", bus)

    @property
    def _data(self) -> dict[str, Any]:  # type: ignore[override]
        # Code ported from the original sometimes pokes ``ud._data``.
        return self._ud._data

    def _who(self) -> str:
        if self._path and self._writer:
            return f"state {self._path}/{self._writer}"
        return f"state {self._writer!r}" if self._writer else "this state"

    def _read(self, key: str) -> Any:
        if key not in self._in:
            declared = ", ".join(sorted(self._in)) or "none"
            raise UndeclaredKeyError(
                f"{self._who()} read userdata key {key!r}, which is not declared as an input "
                f"key; declared input keys: {declared}"
            )
        target = self._remap.get(key, key)
        data = self._d
        if data is None:
            value = self._ud[target]
        else:
            value = data.get(target, _MISSING)
            if value is _MISSING:
                raise UserDataKeyError(key, data, target)
        if key in self._rw:
            return value
        return get_const(value)

    def _write(self, key: str, value: Any) -> None:
        if key not in self._out:
            declared = ", ".join(sorted(self._out)) or "none"
            raise InvalidUserCodeError(
                f"{self._who()} wrote userdata key {key!r}, which is not declared as an output "
                f"key; declared output keys: {declared}"
            )
        target = self._remap.get(key, key)
        if self._d is None:
            self._ud[target] = value
        else:
            self._d[target] = value
        bus = self._bus
        if bus is not None and bus.listeners:
            self._written(bus, target, value)

    def _written(self, bus: EventBus, target: str, value: Any) -> None:
        """Tell the tree's listeners that ``target`` of the container was written."""
        t, thread = stamp()
        if bus.sinks:
            # Captures hold values that cannot change: a mutable one as it is now.
            bus.capture(
                (UserdataWritten, self._path, t, thread, target, frozen(value), self._writer)
            )
        if bus.event_listeners:
            bus.deliver(
                UserdataWritten(
                    path=self._path,
                    time=t,
                    thread=thread,
                    key=target,
                    value=value,
                    writer=self._writer,
                )
            )

    def _take(self, key: str) -> Any:
        # A key this view does not declare as an input has no value for the copier.
        if key not in self._in:
            return MISSING
        target = self._remap.get(key, key)
        data = self._d
        return self._ud._take(target) if data is None else data.get(target, MISSING)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return self._read(name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
        else:
            self._write(name, value)

    def __getitem__(self, key: str) -> Any:
        return self._read(key)

    def __setitem__(self, key: str, value: Any) -> None:
        self._write(key, value)

    def __delitem__(self, key: str) -> None:
        raise InvalidUserCodeError(f"{self._who()} cannot delete userdata key {key!r}")

    def __contains__(self, key: object) -> bool:
        if key not in self._in:
            return False
        target = self._remap.get(key, key)
        return target in (self._ud if self._d is None else self._d)

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def __len__(self) -> int:
        return len(self.keys())

    def __repr__(self) -> str:
        return f"Remapper(in={sorted(self._in)}, out={sorted(self._out)}, remap={self._remap})"

    def keys(self) -> list[str]:
        """The state-local names of the declared input keys that have a value."""
        data = self._ud if self._d is None else self._d
        return [k for k in sorted(self._in) if self._remap.get(k, k) in data]

    def update(self, other: UserData | Mapping[str, Any]) -> None:
        self._ud.update(other)

    def __getstate__(self) -> dict[str, Any]:
        raise TypeError("a Remapper is a view of its container's userdata and cannot be pickled")


# -- fast remappers ----------------------------------------------------------------------
# A Remapper resolves ``ud.key`` in __getattr__, which Python only calls after normal
# attribute lookup has failed (and raised and discarded an AttributeError): about 1 µs
# per access. Containers instead build remappers from a subclass with one property
# per declared key, cached per interface (keys and remapping), so a read is a property
# call and a dict lookup.

_REMAPPER_CLASSES: dict[
    tuple[frozenset[str], frozenset[str], tuple[tuple[str, str], ...]], type[Remapper]
] = {}
_REMAPPER_CACHE: dict[
    tuple[tuple[str, ...], tuple[str, ...], tuple[tuple[str, str], ...]],
    tuple[type[Remapper], frozenset[str], frozenset[str], frozenset[str]],
] = {}


_NO_REMAP: dict[str, str] = {}


def _fast_setattr(self: Remapper, name: str, value: Any) -> None:
    # One Python call per write: the declared output keys of this class are in
    # _writes (state key -> container key); anything else takes the slow path.
    target = self._writes.get(name)
    if target is None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
        else:
            self._write(name, value)  # remapped non-identifier key, or the undeclared-key error
        return
    self._d[target] = value  # type: ignore[index]
    bus = self._bus
    if bus is not None and bus.listeners:
        self._written(bus, target, value)


def _key_property(key: str, target: str, const: bool) -> property:
    def get(self: Remapper) -> Any:
        # Fast classes only ever wrap a plain UserData, so _d is its dict.
        data: dict[str, Any] = self._d  # type: ignore[assignment]
        try:
            value = data[target]
        except KeyError:
            raise UserDataKeyError(key, data, target) from None
        if const and type(value) not in _PLAIN:
            return get_const(value)
        return value

    return property(get)


def make_remapper(
    ud: UserData,
    input_keys: Iterable[str],
    output_keys: Iterable[str],
    remapping: Mapping[str, str] | None = None,
    *,
    path: str = "",
    bus: EventBus | None = None,
    writer: str = "",
    owner: Any = None,
) -> Remapper:
    """A :class:`Remapper` with fast attribute access to the declared keys."""
    # (Views without a remapping share one empty dict, never written: a fresh tree's
    # first run touches one object less per child.)
    remap = dict(remapping) if remapping else _NO_REMAP
    if isinstance(ud, Remapper):
        return Remapper(
            ud, input_keys, output_keys, remap, path=path, bus=bus, writer=writer, owner=owner
        )
    # Keyed on the declaration as given (tuples, as State reports them): no sets are
    # built for an interface seen before. Many states of a machine share one.
    key = (tuple(input_keys), tuple(output_keys), tuple(remap.items()))
    entry = _REMAPPER_CACHE.get(key)
    if entry is None:
        entry = _REMAPPER_CACHE[key] = _remapper_class(frozenset(key[0]), frozenset(key[1]), remap)
    cls, ins, outs, rw = entry
    view = object.__new__(cls)
    set_ = object.__setattr__
    set_(view, "_ud", ud)
    set_(view, "_d", ud._data)
    set_(view, "_in", ins)
    set_(view, "_out", outs)
    set_(view, "_rw", rw)
    set_(view, "_remap", remap)
    set_(view, "_writer", writer)
    view._retarget(*_where(path, bus, owner))
    return view


def _where(path: str, bus: EventBus | None, owner: Any) -> tuple[str, EventBus | None]:
    """The container path and bus of a view, from an ``owner`` state if one is given."""
    if owner is not None:
        return owner.path, owner._rt.bus
    return path, bus


def _remapper_class(
    ins: frozenset[str], outs: frozenset[str], remap: dict[str, str]
) -> tuple[type[Remapper], frozenset[str], frozenset[str], frozenset[str]]:
    signature = (ins, outs, tuple(sorted(remap.items())))
    cls = _REMAPPER_CLASSES.get(signature)
    if cls is None:
        fast = {k for k in ins | outs if k.isidentifier() and not k.startswith("_")}
        fast -= set(dir(Remapper))  # never shadow a method
        namespace: dict[str, Any] = {
            "__slots__": (),
            "__setattr__": _fast_setattr,
            "_writes": {k: remap.get(k, k) for k in outs & fast},
        }
        for key in ins & fast:
            namespace[key] = _key_property(key, remap.get(key, key), key not in outs)
        cls = type("Remapper", (Remapper,), namespace)
        _REMAPPER_CLASSES[signature] = cls
    return cls, ins, outs, ins & outs
