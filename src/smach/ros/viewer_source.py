"""A viewer source that follows a remote executive through its IntrospectionServer.

:class:`RosSource` implements :class:`smach.introspection.source.Source` on top of
:class:`~smach.ros.introspection.IntrospectionClient`::

    from smach.introspection import serve
    from smach.ros.viewer_source import RosSource

    with serve(RosSource("my_server")) as viewer:   # the server's name, as given to
        viewer.wait()                               # IntrospectionServer(name, sm, path)

The structure is assembled from the per-container ``container_structure`` messages
(the root is the server's root path, e.g. ``/SM_ROOT``; a child is a container when
a structure message exists for its path). Status messages only carry the *latest*
state of each container (the server coalesces bursts), so the source cannot replay
every event: each :meth:`RosSource.poll` reads the active states of every active
branch from the latest status messages and emits the difference to what it reported
before as ``container_started`` / ``state_entered`` / ``state_exited`` /
``container_terminated`` records (which fold into exactly that set of active states),
the transitions named by the status ``info``, ``userdata`` snapshots from
``local_data``, and a ``structure`` record when a structure message changes. When it
attaches to an executive that is already running, the first records are a ``resync``.

Messages are JSON (parsed by the client, at most 1 MB); nothing is unpickled or
evaluated, every list and mapping read from them is bounded, and userdata values are
summarised again with :func:`smach.introspection.journal.summarise`.
"""

from __future__ import annotations

import json
import math
import os
import re
import time
from typing import Any

from smach.introspection.journal import MAX_REPR, summarise
from smach.ros._api import rclpy
from smach.ros.introspection import IntrospectionClient

__all__ = ["RosSource"]

#: Bounds on what is read from the topics.
MAX_CONTAINERS = 1000
MAX_CHILDREN = 1000
MAX_EDGES = 5000
MAX_NODES = 20_000
MAX_KEYS = 200
MAX_LABEL = 200

_TRANSITION = re.compile(r"^transition (?P<source>[^:]{1,200}):(?P<outcome>.{1,200})->(?P<target>.{1,200})$")  # fmt: skip
_RETURNED = re.compile(r"^(?P<label>\S{1,200}) returned (?P<outcome>.{1,200})$")
_TERMINATED = re.compile(r"^terminated with outcome (?P<outcome>.{1,200})$")


def _labels(value: Any, limit: int) -> list[str]:
    """The strings of a JSON list (bounded; anything else dropped)."""
    if not isinstance(value, list):
        return []
    return [v for v in value[:limit] if isinstance(v, str) and 0 < len(v) <= MAX_LABEL]


def _text(value: Any, default: str = "") -> str:
    if not isinstance(value, str):
        return default
    return value if len(value) <= MAX_REPR else value[:MAX_REPR] + "…"


def _child(path: str, label: str) -> str:
    return f"{path.rstrip('/')}/{label}"


def _parent(path: str) -> str:
    return path.rsplit("/", 1)[0] or "/"


def _depth(path: str) -> int:
    return len([p for p in path.split("/") if p])


class RosSource:
    """Records of the executive published by the IntrospectionServer ``server_name``.

    ``node``: the rclpy node to discover and subscribe with; without one, the source
    initialises rclpy (if needed) and creates a node of its own, and :meth:`close`
    undoes both. ``root``: the server's root path (found by itself otherwise: the
    shortest container path). Waits up to ``timeout`` seconds for the server's first
    structure message and raises :class:`TimeoutError` when none comes; then gives
    the rest of the tree ``settle`` seconds to arrive.
    """

    def __init__(
        self,
        server_name: str,
        *,
        node: Any = None,
        root: str | None = None,
        timeout: float = 10.0,
        settle: float = 0.3,
        title: str | None = None,
    ) -> None:
        self.server_name = server_name
        self._context: Any = None
        self._own_node = node is None
        if node is None:
            if not rclpy.ok():
                self._context = rclpy.get_default_context()
                # No rclpy signal handlers: Ctrl-C stays a KeyboardInterrupt for the caller
                # (the viewer's wait() then closes this source) and SIGTERM still ends it.
                rclpy.init(
                    context=self._context,
                    signal_handler_options=rclpy.signals.SignalHandlerOptions.NO,
                )
            node = rclpy.create_node(f"smach_viewer_{os.getpid()}_{id(self):x}")
        self._node = node
        self._client = IntrospectionClient(node)
        self._closed = False
        self._root = (root.rstrip("/") or "/") if root else ""
        self._structure_msgs: dict[str, dict[str, Any]] = {}
        self._structure_keys: dict[str, str] = {}
        self._status_msgs: dict[str, dict[str, Any]] = {}
        self._userdata: dict[str, str] = {}
        self._active: list[str] = []
        self._time = 0.0
        self._first_poll = True
        try:
            try:
                self.base = node.resolve_topic_name(server_name.strip().rstrip("/"))
                self._client.watch(server_name)
            except Exception as exc:  # empty, or not a valid ROS name
                reason = str(exc).split(", at ", 1)[0]  # rcl appends its source location
                raise ValueError(f"not a usable server name {server_name!r}: {reason}") from None
            self._wait(timeout, settle)
        except BaseException:
            self.close()
            raise
        self.title = title or f"ROS {self.base} {self._root}"
        self._structure = self._assemble()
        self._header: dict[str, Any] = {
            "kind": "header",
            "format": "smach-journal/1",
            "source": "ros",
            "server": self.base,
            "title": self.title,
            "structure": self._structure,
        }

    # -- Source --------------------------------------------------------------------------------
    @property
    def live(self) -> bool:
        return not self._closed

    def header(self) -> dict[str, Any]:
        return self._header

    def poll(self) -> list[dict[str, Any]]:
        if self._closed:
            return []
        records: list[dict[str, Any]] = []
        paths = self._paths()
        if self._read_structures(paths):
            self._structure = self._assemble()
            records.append(
                {"kind": "structure", "time": self._clock(None), "structure": self._structure}
            )
        changed: list[str] = []
        for path in paths:
            status = self._client.status(self.server_name, path)
            if status is not None and status is not self._status_msgs.get(path):
                self._status_msgs[path] = status
                changed.append(path)
        if changed:
            stamps = [t for t in (self._stamp(p) for p in changed) if t is not None]
            t = self._clock(max(stamps) if stamps else None)
            if not self._first_poll:
                records.extend(self._transitions(changed))
            records.extend(self._activity(t))
            records.extend(self._userdata_records(changed, t))
        self._first_poll = False
        return records

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._client.destroy()
        finally:
            if self._own_node and self._node.context.ok():
                self._node.destroy_node()
            if self._context is not None and self._context.ok():
                rclpy.shutdown(context=self._context)

    # -- discovery -----------------------------------------------------------------------------
    def _paths(self) -> list[str]:
        return self._client.paths(self.server_name)[:MAX_CONTAINERS]

    def _wait(self, timeout: float, settle: float) -> None:
        deadline = time.monotonic() + timeout
        seen = 0
        quiet_since = time.monotonic()
        while True:
            paths = self._paths()
            now = time.monotonic()
            if len(paths) != seen:
                seen = len(paths)
                quiet_since = now
            root = self._root or self._find_root(paths)
            if root in paths and now - quiet_since >= settle:
                self._root = root
                self._read_structures(paths)
                return
            if now >= deadline:
                if root in paths:  # still growing after the timeout: take what is there
                    self._root = root
                    self._read_structures(paths)
                    return
                others = [n for n in self._client.get_servers() if n != self.base]
                servers = ", ".join(others[:20]) or "none"
                wanted = f" with root {self._root}" if self._root else ""
                raise TimeoutError(
                    f"no introspection server {self.base}{wanted} published its structure "
                    f"within {timeout:g} s (servers seen: {servers})"
                )
            time.sleep(0.05)

    @staticmethod
    def _find_root(paths: list[str]) -> str:
        known = set(paths)
        roots = [p for p in paths if p == "/" or _parent(p) not in known]
        return min(roots, key=lambda p: (_depth(p), p)) if roots else ""

    def _read_structures(self, paths: list[str]) -> bool:
        """Note new structure messages; True when one changed the structure."""
        changed = False
        for path in paths:
            message = self._client.structure(self.server_name, path)
            if message is None or message is self._structure_msgs.get(path):
                continue
            self._structure_msgs[path] = message
            key = json.dumps(
                {k: v for k, v in message.items() if k not in ("stamp", "server")},
                sort_keys=True,
                default=str,
            )
            if self._structure_keys.get(path) != key:
                self._structure_keys[path] = key
                changed = True
        if changed and not self._root_fixed():
            self._root = self._find_root(list(self._structure_msgs)) or self._root
        return changed

    def _root_fixed(self) -> bool:
        return bool(self._root) and self._root in self._structure_msgs

    # -- structure -------------------------------------------------------------------------------
    def _assemble(self) -> dict[str, Any]:
        budget = [MAX_NODES]
        label = self._root.rsplit("/", 1)[-1] or "ROOT"
        return self._node_dict(self._root, label, "Container", (), budget)

    def _node_dict(
        self, path: str, label: str, type_name: str, outcomes: tuple[str, ...], budget: list[int]
    ) -> dict[str, Any]:
        budget[0] -= 1
        message = self._structure_msgs.get(path)
        node: dict[str, Any] = {
            "path": path,
            "label": label,
            "type": type_name,
            "outcomes": list(outcomes),
            "input_keys": [],
            "output_keys": [],
            "is_container": message is not None,
        }
        if message is None:
            return node
        children = _labels(message.get("children"), MAX_CHILDREN)
        types = message.get("types")
        types = types if isinstance(types, dict) else {}
        edges: list[dict[str, Any]] = []
        leaf_outcomes: dict[str, dict[str, None]] = {}
        raw_edges = message.get("edges")
        for edge in raw_edges[:MAX_EDGES] if isinstance(raw_edges, list) else ():
            if not isinstance(edge, dict):
                continue
            source, outcome, target = edge.get("source"), edge.get("outcome"), edge.get("target")
            if not (isinstance(source, str) and 0 < len(source) <= MAX_LABEL):
                continue
            if not (isinstance(outcome, str) and 0 < len(outcome) <= MAX_LABEL):
                continue
            target = target[:MAX_LABEL] if isinstance(target, str) and target else outcome
            edges.append(
                {
                    "source": source,
                    "outcome": outcome,
                    "target": target,
                    "terminal": target not in children,
                }
            )
            leaf_outcomes.setdefault(source, {})[outcome] = None
        node["outcomes"] = _labels(message.get("container_outcomes"), MAX_CHILDREN)
        node["edges"] = edges
        status = self._status_msgs.get(path) or self._client.status(self.server_name, path)
        node["initial_states"] = _labels((status or {}).get("initial_states"), MAX_CHILDREN)
        child_nodes = []
        for child in children:
            if budget[0] <= 0:
                break
            child_outcomes = tuple(leaf_outcomes.get(child, ()))
            child_type = _text(types.get(child), "State")[:MAX_LABEL]
            child_nodes.append(
                self._node_dict(_child(path, child), child, child_type, child_outcomes, budget)
            )
        node["children"] = child_nodes
        return node

    # -- status ------------------------------------------------------------------------------------
    def _stamp(self, path: str) -> float | None:
        stamp = self._status_msgs.get(path, {}).get("stamp")
        if isinstance(stamp, int | float) and math.isfinite(stamp):
            return float(stamp)
        return None

    def _clock(self, stamp: float | None) -> float:
        """Record time: the server's stamps, never going backwards."""
        self._time = max(self._time, time.time() if stamp is None else stamp)
        return self._time

    def _info(self, path: str) -> str:
        return _text(self._status_msgs.get(path, {}).get("info"))

    def _active_paths(self) -> list[str]:
        """Every active path, parents first, read from the latest status messages."""
        root = self._root
        status = self._status_msgs.get(root)
        if status is None or not _labels(status.get("active_states"), MAX_CHILDREN):
            return []
        found = [root]
        stack = [root]
        while stack and len(found) < MAX_NODES:
            path = stack.pop(0)
            status = self._status_msgs.get(path)
            if status is None:
                continue
            for label in _labels(status.get("active_states"), MAX_CHILDREN):
                child = _child(path, label)
                found.append(child)
                stack.append(child)
        return found

    def _outcome(self, path: str) -> str | None:
        """The outcome ``path`` returned, as far as the status ``info`` tells."""
        label = path.rsplit("/", 1)[-1]
        info = self._info(_parent(path)) if path != self._root else ""
        match = _TRANSITION.match(info)
        if match and match["source"] == label:
            return match["outcome"]
        match = _RETURNED.match(info)
        if match and match["label"] == label:
            return match["outcome"]
        match = _TERMINATED.match(self._info(path))
        return match["outcome"] if match else None

    def _transitions(self, changed: list[str]) -> list[dict[str, Any]]:
        records = []
        for path in changed:
            match = _TRANSITION.match(self._info(path))
            if match:
                records.append(
                    {
                        "kind": "transition",
                        "path": path,
                        "time": self._clock(self._stamp(path)),
                        "source": match["source"],
                        "outcome": match["outcome"],
                        "target": match["target"],
                    }
                )
        return records

    def _activity(self, t: float) -> list[dict[str, Any]]:
        active = self._active_paths()
        if self._first_poll:
            self._active = active
            if not active:
                return []
            return [
                {
                    "kind": "resync",
                    "path": self._root,
                    "time": t,
                    "active": active,
                    "reason": f"attached to the running executive {self.base}",
                }
            ]
        now = set(active)
        before = set(self._active)
        records: list[dict[str, Any]] = []
        for path in sorted(before - now, key=_depth, reverse=True):
            outcome = self._outcome(path)
            if path == self._root:
                records.append({"kind": "container_terminated", "path": path, "time": t,
                                "terminal_states": [], "outcome": outcome})  # fmt: skip
            else:
                records.append({"kind": "state_exited", "path": path, "time": t,
                                "label": path.rsplit("/", 1)[-1], "outcome": outcome})  # fmt: skip
        for path in active:
            if path in before:
                continue
            if path == self._root:
                status = self._status_msgs.get(path, {})
                records.append({"kind": "container_started", "path": path, "time": t,
                                "container_type": "",
                                "initial_states": _labels(status.get("initial_states"), 100)})  # fmt: skip
            else:
                records.append({"kind": "state_entered", "path": path, "time": t,
                                "label": path.rsplit("/", 1)[-1]})  # fmt: skip
        self._active = active
        return records

    def _userdata_records(self, changed: list[str], t: float) -> list[dict[str, Any]]:
        records = []
        for path in changed:
            data = self._status_msgs[path].get("local_data")
            if not isinstance(data, dict):
                continue
            items = list(data.items())
            values = {_text(str(k)): summarise(v) for k, v in items[:MAX_KEYS]}
            if len(items) > MAX_KEYS:
                values["…"] = f"{len(items) - MAX_KEYS} more"
            text = json.dumps(values, sort_keys=True, default=str)
            if self._userdata.get(path) != text:
                self._userdata[path] = text
                records.append({"kind": "userdata", "path": path, "time": t, "values": values})
        return records
