"""Values of a simulated world as JSON data, and back, without losing their types.

A world's checkpoint must give back exactly the world that was saved: a set stays a
set, a tuple a tuple, a random generator continues where it stopped. :func:`encode`
writes Python values as JSON with small tags for what JSON lacks, :func:`decode`
reads them back:

==========================  =============================================
value                       JSON
==========================  =============================================
None, bool, int, str        themselves
float                       itself (``{"float": "inf"}`` when not finite)
list                        a list
tuple                       ``{"tuple": [...]}``
set, frozenset of facts     ``{"facts": ["at r1 kitchen", ...]}`` (sorted)
other set, frozenset        ``{"set": [...]}``, ``{"frozenset": [...]}`` (sorted)
dict                        ``{"dict": [[key, value], ...]}``
dataclass instance          ``{"dataclass": "module:Name", "fields": {...}}``
random.Random               ``{"random": [version, [...], gauss]}``
==========================  =============================================

Facts (tuples of words) get the compact form, so a journal's checkpoint changes
name the facts that changed (see :mod:`smach.introspection.delta`). Anything else
is an error naming the value's type. Nothing is imported while decoding: a
dataclass is rebuilt only if its module is loaded already (a checkpoint is data,
not code).
"""

from __future__ import annotations

import dataclasses
import json
import math
import random
import sys
from typing import Any

from plan_bridge.errors import PlanBridgeError

__all__ = ["SnapshotError", "decode", "encode"]


class SnapshotError(PlanBridgeError, ValueError):
    """A value that cannot be saved, or saved data that cannot be read back."""


def encode(value: Any, where: str = "value") -> Any:
    """``value`` as JSON data (see the module documentation); ``where`` names it in errors."""
    kind = type(value)
    if value is None or kind in (bool, int, str):
        return value
    if kind is float:
        return value if math.isfinite(value) else {"float": repr(value)}
    if kind is list:
        return [encode(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if kind is tuple:
        return {"tuple": [encode(v, f"{where}[{i}]") for i, v in enumerate(value)]}
    if kind in (set, frozenset):
        facts = _facts(value)
        if facts is not None:
            return {"facts": facts} if kind is set else {"frozen_facts": facts}
        items = [encode(v, f"{where} item") for v in value]
        return {kind.__name__: sorted(items, key=_order)}
    if kind is dict:
        return {"dict": [[encode(k, f"{where} key"), encode(v, f"{where}[{k!r}]")] for k, v in value.items()]}  # fmt: skip
    if kind is random.Random:
        version, internal, gauss = value.getstate()
        return {"random": [version, list(internal), gauss]}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            "dataclass": f"{kind.__module__}:{kind.__qualname__}",
            "fields": {
                f.name: encode(getattr(value, f.name), f"{where}.{f.name}")
                for f in dataclasses.fields(value)
            },
        }
    raise SnapshotError(
        f"{where}: a {kind.__name__} cannot be saved in a snapshot; allowed: None, bool, "
        f"int, float, str, list, tuple, set, frozenset, dict, dataclasses, random.Random"
    )


def _facts(value: set[Any] | frozenset[Any]) -> list[str] | None:
    """The sorted ``"word word ..."`` texts of a set of facts (tuples of words without
    spaces), or None if it holds anything else."""
    texts = []
    for item in value:
        if type(item) is not tuple or not item:
            return None
        try:
            text = " ".join(item)
        except TypeError:  # not all strings
            return None
        if len(text.split()) != len(item):  # a word with a space, or an empty one
            return None
        texts.append(text)
    texts.sort()
    return texts


def _order(item: Any) -> str:
    return json.dumps(item, sort_keys=True)


def decode(data: Any, where: str = "value") -> Any:
    """The value :func:`encode` wrote."""
    if data is None or type(data) in (bool, int, float, str):
        return data
    if type(data) is list:
        return [decode(v, f"{where}[{i}]") for i, v in enumerate(data)]
    if type(data) is not dict or len(data) not in (1, 2):
        raise SnapshotError(f"{where}: {str(data)[:80]!r} is not saved data")
    tag = next(iter(data))
    body = data[tag]
    try:
        if tag == "float":
            return float(body)
        if tag == "tuple":
            return tuple(decode(v, where) for v in body)
        if tag in ("facts", "frozen_facts"):
            facts = (tuple(f.split()) for f in body)
            return set(facts) if tag == "facts" else frozenset(facts)
        if tag == "set":
            return {decode(v, where) for v in body}
        if tag == "frozenset":
            return frozenset(decode(v, where) for v in body)
        if tag == "dict":
            return {decode(k, where): decode(v, f"{where}[{k!r}]") for k, v in body}
        if tag == "random":
            generator = random.Random()
            version, internal, gauss = body
            generator.setstate((version, tuple(internal), gauss))
            return generator
        if tag == "dataclass":
            return _dataclass(body, data["fields"], where)
    except SnapshotError:
        raise
    except (TypeError, ValueError, KeyError) as exc:
        raise SnapshotError(f"{where}: cannot read {tag!r} data: {exc}") from exc
    raise SnapshotError(f"{where}: unknown tag {tag!r}")


def _dataclass(name: str, fields: dict[str, Any], where: str) -> Any:
    module_name, _, qualname = name.partition(":")
    module = sys.modules.get(module_name)
    cls: Any = module
    for part in qualname.split("."):
        cls = getattr(cls, part, None)
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise SnapshotError(f"{where}: {name} is not a loaded dataclass")
    values = {key: decode(value, f"{where}.{key}") for key, value in fields.items()}
    init = {f.name for f in dataclasses.fields(cls) if f.init}
    made = cls(**{k: v for k, v in values.items() if k in init})
    for key, value in values.items():
        if key not in init:
            object.__setattr__(made, key, value)
    return made
