"""The world of a robot node, seen from the executive of ``plan-bridge run --ros``."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from plan_bridge.belief import Observation
from plan_bridge.errors import PlanBridgeError
from plan_bridge.execution.clock import WALL_CLOCK, Clock, PacedClock
from plan_bridge.planning.types import PlanStep

__all__ = ["RobotWorld"]


class RobotNode(Protocol):
    """What the world reads of its robot node's connection
    (a :class:`~plan_bridge.ros.connection.RobotConnection`)."""

    node: Any
    prefix: str
    start_robot: bool
    robot_info: dict[str, Any]

    def info(self, timeout: float = 5.0) -> dict[str, Any] | None: ...


class RobotWorld:
    """The world of a robot node, seen from the executive (a
    :class:`~plan_bridge.execution.world.World`).

    The robot's skills act on it over ROS 2; the executive keeps the robot's pace (its
    :attr:`clock`) and learns the robot's numbers (faults, simulated time) from its
    ``info`` service.
    It cannot be saved (a run with ``--ros`` is not resumable): its state lives in the
    robot's process.
    """

    time_scale = 0.0  # the robot's pace is its own (``--time-scale`` of its process)

    def __init__(self, robot: RobotNode) -> None:
        self.robot = robot
        self._info: dict[str, Any] = {}
        # The robot paces its world at its time scale: simulated seconds are wall
        # seconds divided by it (a robot that does not pace, on the wall clock).
        scale = robot.robot_info.get("time_scale")
        paced = isinstance(scale, (int, float)) and scale > 0
        self._clock: Clock = PacedClock(float(scale or 0)) if paced else WALL_CLOCK
        self._origin = self._clock.now()

    @property
    def clock(self) -> Clock:
        """The mission's clock: :class:`~plan_bridge.execution.clock.PacedClock` at the
        robot's time scale (its simulated seconds as they pass), else the wall clock."""
        return self._clock

    def now(self) -> float:
        return self._clock.now() - self._origin

    def adopt(self, step: PlanStep, observations: Sequence[Observation]) -> None:
        """Nothing to take: the robot's world changed by itself. (A user's skill run in
        the executive's process beside a *simulated* robot node is not seen by the
        node's simulated world: write it as a skill of the robot node instead.)"""

    def sense(self, steps: Sequence[PlanStep]) -> list[Observation]:
        """The robot node reports what it sees with each skill's result; it has no
        separate sensing service, so there is nothing more to sense here."""
        return []

    def latest_info(self) -> dict[str, Any]:
        """The robot's ``info`` now, or the last one it gave (it may be gone)."""
        info = self.robot.info() if self.robot.node is not None else None
        if info is not None:
            self._info = info
        return self._info

    @property
    def faults_injected(self) -> int | None:
        value = self.latest_info().get("faults_injected")
        return None if value is None else int(value)

    def goal_reached(self) -> bool:
        return bool(self.latest_info().get("goal_reached", False))

    def snapshot(self) -> dict[str, Any] | None:
        return None

    def restore(self, data: dict[str, Any]) -> None:
        raise PlanBridgeError(
            "a robot node's world cannot be restored: its state lives in its own process"
        )

    def abandon_running(self) -> None:
        """Nothing to undo here: the robot node ends its own actions."""

    def figures(self) -> dict[str, Any]:
        """The robot's numbers from its ``info``: faults, simulated time, and its world's
        own figures (a pyrobosim world's ``distance_m``, ``battery``, ``battery_used``,
        ``world_changes``), as a run in one process reports them."""
        info = self.latest_info() or None
        robot = self.robot
        own = info.get("figures") if info is not None else None
        return {
            **(own if isinstance(own, dict) else {}),
            "faults_injected": None if info is None else info.get("faults_injected"),
            "sim_time_s": None if info is None else info.get("sim_time"),
            "ros": {
                "prefix": robot.prefix,
                "robot": "started" if robot.start_robot else "connected",
                "robot_info": info,
            },
        }
