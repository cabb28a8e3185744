"""Introspection: the event stream, structure snapshots and their renderings.

The browser viewer is imported lazily (``smach.introspection.serve``), so that
``import smach`` does not load the HTTP server.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from smach.introspection.server import ViewerServer, serve
    from smach.introspection.source import JournalSource, LiveSource, Source

__all__ = ["JournalSource", "LiveSource", "Source", "ViewerServer", "serve"]

_LAZY = {
    "serve": "smach.introspection.server",
    "ViewerServer": "smach.introspection.server",
    "LiveSource": "smach.introspection.source",
    "JournalSource": "smach.introspection.source",
    "Source": "smach.introspection.source",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'smach.introspection' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(module), name)
