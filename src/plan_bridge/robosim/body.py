"""What a robosim skill asks of a robot's body: plan a drive, drive it, act, look.

The skill machines of :mod:`.skills` decide *what* to do next (``PLAN`` -> ``DRIVE`` ->
``LOOK``, ``ACT`` -> ``LOOK``, a preempt); a :class:`Body` does it in the world. A
:class:`WorldBody` does it in a :class:`~.world.RobosimWorld` of the same process. A
robot that runs as a process of its own (``plan-bridge run --ros`` on a pyrobosim
world) runs the same machines against :class:`~plan_bridge.ros.body_client.RemoteBody`,
which asks the world's process over ROS 2 for each of these calls.

Every call names the robot and the step's action and arguments (as the plan has them);
a drive gets back the *route* its ``plan`` made (an opaque handle: the route object
here, a number kept by the world's process across processes).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, Protocol

from plan_bridge.belief import Observation
from plan_bridge.robosim.actions import act, cross_path, drive_route, follow, plan_route
from plan_bridge.robosim.results import ActionResult
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["Body", "Preempted", "WorldBody"]

Preempted = Callable[[], bool]


class Body(Protocol):
    """A robot's body in a pyrobosim world, as the robosim skills use it."""

    def plan(self, robot: str, action: str, args: Sequence[str]) -> tuple[Any, ActionResult]:
        """The route of a ``navigate`` or ``cross`` step (None when there is nothing to
        drive: the result then says why, or that the robot is there already)."""
        ...

    def drive(
        self, robot: str, action: str, args: Sequence[str], route: Any, preempted: Preempted
    ) -> ActionResult:
        """Drive the route ``plan`` gave; a preempt stops the robot where it is."""
        ...

    def act(
        self, robot: str, action: str, args: Sequence[str], preempted: Preempted
    ) -> ActionResult:
        """Any other step: pick, place, open, close, detect, search, charge."""
        ...

    def look(self, robot: str, about: Iterable[str]) -> list[Observation]:
        """What the robot sees now of itself and of the things ``about`` names."""
        ...


class WorldBody:
    """The bodies of a :class:`~.world.RobosimWorld`'s robots, in this process."""

    def __init__(self, world: RobosimWorld) -> None:
        self.world = world

    def plan(self, robot: str, action: str, args: Sequence[str]) -> tuple[Any, ActionResult]:
        world = self.world
        if action == "cross":
            return cross_path(world, world.robot(robot), args[3], args[2])
        return plan_route(world, world.robot(robot), args[2])

    def drive(
        self, robot: str, action: str, args: Sequence[str], route: Any, preempted: Preempted
    ) -> ActionResult:
        world = self.world
        body = world.robot(robot)
        if action != "cross":
            return drive_route(world, body, route, preempted)
        result = follow(world, body, route, preempted)
        if result.status == "SUCCESS":
            world.crossed.setdefault(body.name, []).append(world.name(args[3]))
        return result

    def act(
        self, robot: str, action: str, args: Sequence[str], preempted: Preempted
    ) -> ActionResult:
        return act(self.world, self.world.robot(robot), action, list(args), preempted)

    def look(self, robot: str, about: Iterable[str]) -> list[Observation]:
        return self.world.observe(self.world.robot(robot), about)
