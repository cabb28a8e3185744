"""``--probe``: is each ROS 2 server of a skill map up, with the type the map says?

:func:`probe_skill_map` joins the ROS graph with a context and node of its own and
looks, for every ROS entry of a skill map, at the action server, service server or
topic publishers it names (a name with ``{?param}`` parts once per object of the
problem that can fill them), waiting up to ``timeout`` seconds in all for the
missing ones. A server that is there but serves another type is reported too: the
goal would be refused or never matched. Used by ``plan-bridge check --probe`` and
``plan-bridge skills --probe``.
"""

from __future__ import annotations

import importlib
import itertools
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TextIO

from plan_bridge.skills.ros.conditions import substitute, template_parameters

if TYPE_CHECKING:
    from plan_bridge.skills.ros.entries import RosEntry
    from plan_bridge.skills.skill_map import SkillMap, SkillMapEntry

__all__ = ["ProbeResult", "print_probe", "probe_skill_map"]

#: Seconds between two looks at the ROS graph.
POLL = 0.1


@dataclass(frozen=True)
class ProbeResult:
    """What the probe found for one ROS name of one entry."""

    entry: SkillMapEntry
    name: str
    up: bool
    problem: str = ""
    """Why it is not usable (not up, another type); ``""`` when it is."""

    def __str__(self) -> str:
        ros = self.entry.ros
        assert ros is not None
        what = f"{self.entry.location}: {self.entry.label}: ROS {ros.kind} {self.name} ({ros.type_name})"
        return f"{what}: {'up' if not self.problem else self.problem}"


def ground_names(
    entry: RosEntry, objects_of_type: Callable[[str], Sequence[str]] | None, types: dict[str, str]
) -> list[str]:
    """Every name of ``entry`` with its ``{?param}`` parts filled by the problem's objects."""
    parameters = sorted(set(template_parameters(entry.name)))
    if not parameters:
        return [entry.name]
    if objects_of_type is None:
        return []
    choices = [list(objects_of_type(types[p])) for p in parameters]
    return sorted(
        {
            substitute(entry.name, dict(zip(parameters, chosen, strict=True)))
            for chosen in itertools.product(*choices)
        }
    )


def probe_skill_map(skill_map: SkillMap, task: Any, *, timeout: float = 3.0) -> list[ProbeResult]:
    """Look for the server (or publishers) of every ROS entry of ``skill_map``; ``task``
    gives the objects that fill ``{?param}`` parts of names. Waits up to ``timeout``
    seconds in all."""
    wanted: list[tuple[SkillMapEntry, str]] = []
    objects_of_type = getattr(task, "objects_of_type", None)
    for map_entry in skill_map.entries:
        ros = map_entry.ros
        if ros is None:
            continue
        schema = task.actions[map_entry.action.lower()]
        types = {
            n.lstrip("?").lower(): p.type
            for n, p in zip(schema.parameter_names, schema.parameters, strict=False)
        }
        wanted.extend((map_entry, name) for name in ground_names(ros, objects_of_type, types))
    if not wanted:
        return []
    from smach.ros.rclpy_api import rclpy

    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node(f"plan_bridge_probe_{os.getpid()}", context=context)
    try:
        return _look(node, wanted, time.monotonic() + timeout)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def _look(node: Any, wanted: list[tuple[SkillMapEntry, str]], deadline: float) -> list[ProbeResult]:
    from smach.ros.rclpy_api import ActionClient

    clients: dict[int, Any] = {}
    for index, (map_entry, name) in enumerate(wanted):
        ros = map_entry.ros
        assert ros is not None
        if ros.kind == "action":
            clients[index] = ActionClient(node, ros.interface, name)
        elif ros.kind == "service":
            clients[index] = node.create_client(ros.interface, name)
    found: dict[int, ProbeResult] = {}
    while True:
        for index, (map_entry, name) in enumerate(wanted):
            if index not in found:
                result = _seen(node, map_entry, name, clients.get(index))
                if result is not None:
                    found[index] = result
        if len(found) == len(wanted) or time.monotonic() >= deadline:
            break
        time.sleep(POLL)
    waited = "not up (nothing serves it: is the robot's server running, in the same ROS_DOMAIN_ID?)"
    for client in clients.values():
        client.destroy()
    return [
        found.get(index) or ProbeResult(map_entry, name, False, waited)
        for index, (map_entry, name) in enumerate(wanted)
    ]


def _seen(node: Any, map_entry: SkillMapEntry, name: str, client: Any) -> ProbeResult | None:
    """The result once the server (or a publisher) is there; None while it is not."""
    ros = map_entry.ros
    assert ros is not None
    if ros.kind == "action":
        if not client.server_is_ready():
            return None
        graph: Any = importlib.import_module("rclpy.action")
        types = dict(graph.get_action_names_and_types(node)).get(name, [])
    elif ros.kind == "service":
        if not client.service_is_ready():
            return None
        types = dict(node.get_service_names_and_types()).get(name, [])
    else:
        publishers = node.get_publishers_info_by_topic(name)
        if not publishers:
            return None
        types = sorted({info.topic_type for info in publishers})
    if types and ros.type_name not in types:
        return ProbeResult(
            map_entry, name, True, f"up, but it uses type {', '.join(types)}, not {ros.type_name}"
        )
    return ProbeResult(map_entry, name, True)


def print_probe(
    skill_map: SkillMap | None, task: Any, seconds: float, stream: TextIO | None = None
) -> list[str]:
    """Probe (:func:`probe_skill_map`) and print one ``probe: ...`` line per server to
    ``stream`` (stderr); the lines of those that are not usable."""
    out = stream or sys.stderr
    if skill_map is None or not any(entry.ros is not None for entry in skill_map.entries):
        print("probe: no ROS entries in the skill map", file=out)
        return []
    unusable = []
    for result in probe_skill_map(skill_map, task, timeout=seconds):
        print(f"probe: {result}", file=out)
        if result.problem:
            unusable.append(str(result))
    return unusable
