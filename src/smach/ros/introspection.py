"""Introspection over ROS 2 topics: structure and status of every container, as JSON.

Topics (``std_msgs/String``, one JSON object per message; smach_msgs has no PyPI
wheel, and JSON keeps the payload safe to read anywhere)::

    <server_name>/smach/container_structure   one message per container
    <server_name>/smach/container_status      one message per container

The field names follow smach_msgs (``path``, ``children``, ``internal_outcomes``,
``outcomes_from``, ``outcomes_to``, ``container_outcomes``; ``initial_states``,
``active_states``, ``local_data``, ``info``), with additions (``format``, ``server``,
``stamp``, ``edges``, ``types``). ``local_data`` is a mapping key -> bounded JSON
summary of the value (:func:`smach.introspection.journal.summarise`), never a
pickle. Both topics are reliable and transient-local with one slot per container,
so a client that starts late still gets the latest message of every container.

The server listens to the tree's event stream. The listener only notes which
containers changed and wakes a publisher thread, which coalesces bursts and
publishes; a heartbeat republishes everything every ``update_rate`` seconds.
Execution never waits for the network. Nothing received is unpickled or evaluated:
the client parses JSON of bounded size and ignores anything else.
"""

from __future__ import annotations

import functools
import json
import re
import threading
import time
from collections.abc import Callable
from typing import Any

import smach
from smach.introspection.events import (
    ContainerStarted,
    ContainerTerminated,
    Event,
    StateEntered,
    StateExited,
    Transition,
)
from smach.introspection.journal import summarise
from smach.ros._api import (
    DurabilityPolicy,
    Node,
    QoSProfile,
    ReliabilityPolicy,
    StringMsg,
    rclpy,
)
from smach.ros.executor import (
    SmachExecutor,
    publisher_events,
    seconds,
    subscription_events,
)
from smach.ros.shared_node import ensure_init

__all__ = [
    "FORMAT",
    "STATUS_TOPIC",
    "STRUCTURE_TOPIC",
    "IntrospectionClient",
    "IntrospectionServer",
]

FORMAT = "smach-ros-introspection/1"
STATUS_TOPIC = "/smach/container_status"
STRUCTURE_TOPIC = "/smach/container_structure"
#: Largest message the client accepts (bytes of JSON).
MAX_MESSAGE = 1_000_000
#: Time the publisher waits after a change to gather a burst into one message.
COALESCE = 0.01


def _qos(depth: int) -> Any:
    return QoSProfile(
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )


def _node_name(topic_base: str) -> str:
    """A valid node name made from a server name (``/a/b-c`` -> ``a_b_c``)."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", topic_base.strip("/")) or "smach_introspection"
    return name if name[0].isalpha() else f"smach_{name}"


def _topic_base(server_name: str) -> str:
    name = server_name.strip()
    if not name or name == "/":
        raise smach.InvalidStateError(
            f"introspection server name must not be empty: {server_name!r}"
        )
    return name.rstrip("/")


class IntrospectionServer(Node):  # type: ignore[misc]
    """Publish the structure and status of every container under ``state``.

    ``IntrospectionServer(server_name, state, path)`` as in smach_ros: paths are
    ``path`` for ``state`` and ``path/LABEL`` below it. As in the ROS 2 smach_ros,
    the server *is* an rclpy node named after ``server_name`` (``/`` and other
    characters a node name cannot hold become ``_``), so code that spins it, adds it
    to an executor, logs through it or calls ``destroy_node()`` keeps working; it
    does not need to be spun (the publishers live on smach's helper node). If
    nobody has called ``rclpy.init()``, it is called here (ROS 1 scripts never
    did: ``rospy.init_node`` was enough). ``node`` (new) is the node names are
    resolved against (default: the server itself). Call :meth:`start` (or use
    ``with``, which also destroys the node at the end).
    """

    def __init__(
        self,
        server_name: str,
        state: smach.State,
        path: str = "/SM_ROOT",
        *,
        node: Any = None,
        update_rate: Any = 2.0,
        context: Any = None,
    ) -> None:
        if not path.startswith("/"):
            raise smach.InvalidStateError(f"introspection path must start with '/': {path!r}")
        topic_base = _topic_base(server_name)
        if node is not None:
            context = node.context
        # Set before the node exists: rclpy may destroy a half-built server at shutdown.
        self._running = False
        self._thread: threading.Thread | None = None
        self._status_pub: Any = None
        self._structure_pub: Any = None
        self._control: Any = None  # smach.ros.control.ControlServices, see serve_control
        super().__init__(_node_name(topic_base), context=ensure_init(context))
        self.server_name = topic_base
        self._state = state
        self._root_path = path.rstrip("/") or "/"
        self._period = seconds(update_rate, "update_rate", allow_none=False) or 2.0
        self._node = self if node is None else node
        self._helper = SmachExecutor.for_node(self._node)
        try:
            base = self._node.resolve_topic_name(self.server_name)
        except Exception as exc:
            super().destroy_node()
            raise smach.InvalidStateError(
                f"introspection server name {server_name!r} is not a valid ROS topic name "
                f"(letters, digits, '_' and '/'): {exc}"
            ) from exc
        self.status_topic = base + STATUS_TOPIC
        self.structure_topic = base + STRUCTURE_TOPIC
        self._containers: dict[str, tuple[smach.Container, str]] = {}
        self._dirty: dict[str, str] = {}  # smach path -> info
        self._structure_dirty: set[str] = set()
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self.published = 0

    def serve_control(self, controller: Any, *, actions: Any = None) -> Any:
        """Offer runtime-control services for ``controller`` (see smach/ros/control.py)."""
        from smach.ros.control import ControlServices

        if self._control is not None:
            self._control.close()
        self._control = ControlServices(self, controller, actions=actions)
        return self._control

    # -- life cycle -----------------------------------------------------------------------
    def start(self) -> IntrospectionServer:
        if self._running:
            return self
        self._map_containers()
        depth = max(10, 2 * len(self._containers))
        helper_node = self._helper.node
        self._structure_pub = helper_node.create_publisher(
            StringMsg,
            self.structure_topic,
            _qos(depth),
            event_callbacks=publisher_events(self.structure_topic),
        )
        self._status_pub = helper_node.create_publisher(
            StringMsg,
            self.status_topic,
            _qos(depth),
            event_callbacks=publisher_events(self.status_topic),
        )
        self._running = True
        with self._lock:
            self._structure_dirty.update(self._containers)
            self._dirty.update(dict.fromkeys(self._containers, "Initial state"))
        self._state_listen(True)
        self._thread = threading.Thread(
            target=self._publish_loop, name=f"smach-introspection-{self.server_name}", daemon=True
        )
        self._thread.start()
        self._wake.set()
        return self

    def stop(self) -> None:
        """Stop publishing (listeners detached, publisher thread ended)."""
        if self._control is not None:
            self._control.close()
            self._control = None
        if not self._running:
            return
        self._running = False
        self._state_listen(False)
        self._wake.set()
        if self._thread is not None:
            self._thread.join(5.0)
        helper_node = self._helper.node
        for pub in (self._status_pub, self._structure_pub):
            if pub is not None and self._helper.alive:
                helper_node.destroy_publisher(pub)
        self._status_pub = self._structure_pub = None

    def destroy_node(self) -> None:
        """Stop publishing and remove the server's node from the ROS graph."""
        self.stop()
        if self.context.ok():
            super().destroy_node()

    def clear(self) -> None:
        """Forget the containers (as in smach_ros); :meth:`start` maps them again."""
        with self._lock:
            self._containers.clear()

    def __enter__(self) -> IntrospectionServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.destroy_node()

    def _state_listen(self, on: bool) -> None:
        if isinstance(self._state, smach.Container):
            if on:
                self._state.add_listener(self._on_event)
            else:
                self._state.remove_listener(self._on_event)

    def _map_containers(self) -> None:
        """smach path -> (container, introspection path), for the whole tree."""
        found: dict[str, tuple[smach.Container, str]] = {}

        def walk(state: smach.State, intro_path: str) -> None:
            if not isinstance(state, smach.Container):
                return
            found[state.path or intro_path] = (state, intro_path)
            for label, child in state.get_children().items():
                walk(child, f"{intro_path.rstrip('/')}/{label}")

        walk(self._state, self._root_path)
        with self._lock:
            self._containers = found

    # -- the event listener (execution threads: no I/O, no waiting) -----------------------------
    def _on_event(self, event: Event) -> None:
        if isinstance(event, Transition):
            container = event.path
            info = f"transition {event.source}:{event.outcome}->{event.target}"
        elif isinstance(event, StateEntered | StateExited):
            container = event.path.rsplit("/", 1)[0]
            info = (
                f"entered {event.label}"
                if isinstance(event, StateEntered)
                else f"{event.label} returned {event.outcome}"
            )
        elif isinstance(event, ContainerStarted):
            container = event.path
            info = f"started in {list(event.initial_states)}"
        elif isinstance(event, ContainerTerminated):
            container = event.path
            info = f"terminated with outcome {event.outcome}"
        else:
            return
        with self._lock:
            if isinstance(event, ContainerStarted) or container not in self._containers:
                self._structure_dirty.add(container)
            self._dirty[container] = info
        self._wake.set()

    # -- the publisher thread ---------------------------------------------------------------------
    def _publish_loop(self) -> None:
        next_heartbeat = time.monotonic() + self._period
        while self._running:
            self._wake.wait(max(0.0, next_heartbeat - time.monotonic()))
            if not self._running:
                break
            time.sleep(COALESCE)
            self._wake.clear()
            heartbeat = time.monotonic() >= next_heartbeat
            with self._lock:
                dirty = self._dirty
                structure = self._structure_dirty
                self._dirty = {}
                self._structure_dirty = set()
            if structure - self._containers.keys():
                self._map_containers()
            if heartbeat:
                next_heartbeat = time.monotonic() + self._period
                structure = set(self._containers)
                dirty = {**dict.fromkeys(self._containers, "HEARTBEAT"), **dirty}
            try:
                for smach_path in structure:
                    self._publish_structure(smach_path)
                for smach_path, info in dirty.items():
                    self._publish_status(smach_path, info)
            except Exception as exc:  # the context went down under us
                if self._running and self._helper.alive:
                    smach.logerr(f"introspection server {self.server_name}: {exc!r}")
                    continue
                break

    def _publish(self, publisher: Any, data: dict[str, Any]) -> None:
        if publisher is None:
            return
        message = StringMsg()
        message.data = json.dumps(data, separators=(",", ":"))
        publisher.publish(message)
        self.published += 1

    def _publish_structure(self, smach_path: str) -> None:
        entry = self._containers.get(smach_path)
        if entry is None:
            return
        container, intro_path = entry
        children = container.get_children()
        edges = container.get_internal_edges()
        self._publish(
            self._structure_pub,
            {
                "format": FORMAT,
                "server": self.server_name,
                "stamp": time.time(),
                "path": intro_path,
                "children": list(children),
                "types": {label: type(child).__name__ for label, child in children.items()},
                "internal_outcomes": [outcome for outcome, _, _ in edges],
                "outcomes_from": [source for _, source, _ in edges],
                "outcomes_to": [str(target) for _, _, target in edges],
                "container_outcomes": list(container.get_registered_outcomes()),
                "edges": [
                    {
                        "outcome": outcome,
                        "source": source,
                        "target": target or outcome,
                        "terminal": not target or target not in children,
                    }
                    for outcome, source, target in edges
                ],
            },
        )

    def _publish_status(self, smach_path: str, info: str) -> None:
        entry = self._containers.get(smach_path)
        if entry is None:
            return
        container, intro_path = entry
        self._publish(
            self._status_pub,
            {
                "format": FORMAT,
                "server": self.server_name,
                "stamp": time.time(),
                "path": intro_path,
                "initial_states": list(container.get_initial_states()),
                "active_states": list(container.get_active_states()),
                "local_data": _summarise_userdata(container.userdata),
                "info": info,
            },
        )


def _summarise_userdata(ud: smach.UserData) -> dict[str, Any]:
    # Execution may write keys while this runs in the publisher thread: copy the
    # dict first (atomic under the GIL), then summarise the copy.
    for _ in range(3):
        try:
            data = dict(ud._data)
            return {str(key): summarise(value) for key, value in data.items()}
        except RuntimeError:  # a nested dict changed size while being read
            continue
    return {"…": "userdata changed while being read"}


class IntrospectionClient:
    """Read what introspection servers publish: latest structure and status per path.

    ``IntrospectionClient(node=None)``: uses ``node`` to discover servers (or a node
    of its own) and smach's helper node to subscribe. Messages that are not JSON
    objects of at most :data:`MAX_MESSAGE` bytes in the expected format are ignored.
    """

    def __init__(self, node: Any = None, *, context: Any = None) -> None:
        # A string is the node name of the ROS 2 original: IntrospectionClient(node_name).
        self._own_node = node is None or isinstance(node, str)
        if self._own_node:
            name = node if isinstance(node, str) else "smach_introspection_client"
            node = rclpy.create_node(name, context=ensure_init(context))
        self._node = node
        self._helper = SmachExecutor.for_node(node)
        self._lock = threading.Condition()
        self._subscriptions: dict[str, list[Any]] = {}
        self._structure: dict[tuple[str, str], dict[str, Any]] = {}
        self._status: dict[tuple[str, str], dict[str, Any]] = {}
        self.ignored = 0

    def get_servers(self) -> list[str]:
        """Names of the servers currently publishing status (found in the ROS graph)."""
        servers = []
        for name, types in self._node.get_topic_names_and_types():
            if name.endswith(STATUS_TOPIC) and "std_msgs/msg/String" in types:
                servers.append(name[: -len(STATUS_TOPIC)])
        return sorted(servers)

    def watch(self, server_name: str) -> None:
        """Subscribe to ``server_name``'s topics (done by the getters on first use)."""
        base = self._node.resolve_topic_name(_topic_base(server_name))
        with self._lock:
            if base in self._subscriptions:
                return
            self._subscriptions[base] = []
        helper_node = self._helper.node
        subs = [
            helper_node.create_subscription(
                StringMsg,
                base + suffix,
                functools.partial(self._on_message, base, store=store),
                _qos(100),
                callback_group=self._helper.callback_group,
                event_callbacks=subscription_events(base + suffix),
            )
            for suffix, store in ((STRUCTURE_TOPIC, self._structure), (STATUS_TOPIC, self._status))
        ]
        with self._lock:
            self._subscriptions[base] = subs

    def _on_message(
        self, base: str, msg: Any, store: dict[tuple[str, str], dict[str, Any]]
    ) -> None:
        text = msg.data
        data: Any = None
        if isinstance(text, str) and len(text) <= MAX_MESSAGE:
            try:
                data = json.loads(text)
            except ValueError:
                data = None
        if (
            not isinstance(data, dict)
            or data.get("format") != FORMAT
            or not isinstance(data.get("path"), str)
        ):
            with self._lock:
                self.ignored += 1
            return
        with self._lock:
            store[(base, data["path"])] = data
            self._lock.notify_all()

    def _key(self, server_name: str, path: str) -> tuple[str, str]:
        self.watch(server_name)
        return self._node.resolve_topic_name(_topic_base(server_name)), path

    def structure(self, server_name: str, path: str) -> dict[str, Any] | None:
        """The latest structure message of the container at ``path``."""
        key = self._key(server_name, path)
        with self._lock:
            return self._structure.get(key)

    def status(self, server_name: str, path: str) -> dict[str, Any] | None:
        """The latest status message of the container at ``path``."""
        key = self._key(server_name, path)
        with self._lock:
            return self._status.get(key)

    def paths(self, server_name: str) -> list[str]:
        """Container paths seen so far for ``server_name``."""
        base, _ = self._key(server_name, "")
        with self._lock:
            return sorted({p for (b, p) in self._structure if b == base})

    def wait_for_status(
        self,
        server_name: str,
        path: str,
        predicate: Callable[[dict[str, Any]], bool] = lambda status: True,
        timeout: float = 5.0,
    ) -> dict[str, Any] | None:
        """Wait until the latest status at ``path`` satisfies ``predicate`` (or None)."""
        key = self._key(server_name, path)
        deadline = time.monotonic() + timeout
        with self._lock:
            while True:
                status = self._status.get(key)
                if status is not None and predicate(status):
                    return status
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._lock.wait(left)

    def wait_for_structure(
        self, server_name: str, path: str, timeout: float = 5.0
    ) -> dict[str, Any] | None:
        key = self._key(server_name, path)
        deadline = time.monotonic() + timeout
        with self._lock:
            while key not in self._structure:
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._lock.wait(left)
            return self._structure[key]

    def destroy(self) -> None:
        with self._lock:
            subs = [s for group in self._subscriptions.values() for s in group]
            self._subscriptions.clear()
        if self._helper.alive:
            for sub in subs:
                self._helper.node.destroy_subscription(sub)
        if self._own_node and self._node.context.ok():
            self._node.destroy_node()
