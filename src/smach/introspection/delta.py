"""Changes between two JSON values, so that a journal writes what changed, not everything.

A checkpoint of a mission holds the belief, the plan still to do, the report and the
simulated world: hundreds of facts, of which a step changes a handful. Written whole
after every step, checkpoints were most of a journal (about 10 KB per action for a
small mission, growing with the problem). :func:`diff` gives the change from one
value to the next and :func:`patch` applies it:

* ``{"=": value}``: replaced;
* ``{"{}": {key: change, ...}, "-": [key, ...]}``: a mapping whose entries changed
  (``-``: removed keys);
* ``{"[]": [start, stop, items]}``: a list whose ``[start:stop]`` became ``items``
  (the common head and tail are kept: a plan losing its first step, a list growing
  at its end);
* ``{"at": [[index, change], ...]}``: a list of the same length whose items at these
  indexes changed (the state of a random generator inside a world's snapshot);
* ``{"set": [removed, added]}``: a sorted list of distinct strings (facts) that lost
  and gained these.

A change is plain JSON. :data:`SAME` means no change.
"""

from __future__ import annotations

from typing import Any, Final

__all__ = ["SAME", "diff", "patch"]

SAME: Final = None
"""What :func:`diff` returns when nothing changed."""


def diff(old: Any, new: Any) -> dict[str, Any] | None:
    """The change from ``old`` to ``new`` (JSON values), or :data:`SAME`."""
    if type(old) is type(new) and old == new:
        return SAME
    if type(old) is dict and type(new) is dict:
        changed: dict[str, Any] = {}
        for key, value in new.items():
            if key not in old:
                changed[key] = {"=": value}
            else:
                change = diff(old[key], value)
                if change is not SAME:
                    changed[key] = change
        removed = [key for key in old if key not in new]
        out: dict[str, Any] = {"{}": changed}
        if removed:
            out["-"] = removed
        return out
    if type(old) is list and type(new) is list:
        return _list_change(old, new)
    return {"=": new}


def _list_change(old: list[Any], new: list[Any]) -> dict[str, Any]:
    n, m = len(old), len(new)
    if m >= n and new[:n] == old:  # grew at the end (steps executed so far)
        return {"[]": [n, n, new[n:]]}
    if m <= n and old[n - m :] == new:  # lost its head (the plan still to do)
        return {"[]": [0, n - m, []]}
    if _sorted_strings(old) and _sorted_strings(new):
        before, after = set(old), set(new)
        if len(before) == n and len(after) == m:
            return {"set": [sorted(before - after), sorted(after - before)]}
    head = 0
    limit = min(n, m)
    while head < limit and old[head] == new[head]:
        head += 1
    tail = 0
    while tail < limit - head and old[n - 1 - tail] == new[m - 1 - tail]:
        tail += 1
    if n == m and n - tail - head <= 8:  # a few items changed in place (a list in a list)
        return {
            "at": [[i, diff(old[i], new[i])] for i in range(head, n - tail) if old[i] != new[i]]
        }
    return {"[]": [head, n - tail, new[head : m - tail]]}


def _sorted_strings(values: list[Any]) -> bool:
    return all(type(v) is str for v in values) and values == sorted(values)


def patch(old: Any, change: dict[str, Any] | None) -> Any:
    """``old`` with ``change`` applied (``old`` is not modified)."""
    if change is SAME:
        return old
    if not isinstance(change, dict) or len(change) not in (1, 2):
        raise ValueError(f"not a change: {change!r}")
    if "=" in change:
        return change["="]
    if "{}" in change:
        if not isinstance(old, dict):
            raise ValueError(f"a mapping change for a {type(old).__name__}")
        out = {key: value for key, value in old.items() if key not in change.get("-", ())}
        for key, sub in change["{}"].items():
            out[key] = patch(old.get(key), sub)
        return out
    if "[]" in change:
        if not isinstance(old, list):
            raise ValueError(f"a list change for a {type(old).__name__}")
        start, stop, items = change["[]"]
        return [*old[:start], *items, *old[stop:]]
    if "at" in change:
        if not isinstance(old, list):
            raise ValueError(f"a list change for a {type(old).__name__}")
        out_list = list(old)
        for index, sub in change["at"]:
            out_list[index] = patch(old[index], sub)
        return out_list
    if "set" in change:
        if not isinstance(old, list):
            raise ValueError(f"a set change for a {type(old).__name__}")
        removed, added = change["set"]
        return sorted((set(old) - set(removed)) | set(added))
    raise ValueError(f"not a change: {change!r}")
