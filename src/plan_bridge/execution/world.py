"""The :class:`World` a mission acts on, as the executive and the mission runner see it.

What the executive *believes* of the world is :class:`plan_bridge.belief.Belief`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol

from plan_bridge.belief.facts import Observation

if TYPE_CHECKING:
    from plan_bridge.execution.clock import Clock
    from plan_bridge.planning.types import PlanStep

__all__ = ["World"]


class World(Protocol):
    """The world a mission acts on, as the executive and the mission runner see it.

    Implemented by the symbolic :class:`~plan_bridge.execution.simulation.SimulatedWorld`
    (and its subclasses: :class:`~plan_bridge.execution.timed_world.TimedWorld`, the
    domains' worlds) and by the ROS 2 robot seen from the executive
    (:class:`~plan_bridge.ros.robot_world.RobotWorld`). Skills act on the world; the
    executive never reads its truth, only what skills observe and what :meth:`sense`
    returns. The skill contract (docs/plan-bridge.md) says what each call means.
    """

    #: Wall seconds per simulated second (0: as fast as it goes). A world on the wall
    #: clock (a real robot) keeps 0 and ignores it.
    time_scale: float

    @property
    def clock(self) -> Clock:
        """The world's clock: a simulated world's :class:`~plan_bridge.execution.clock.SimClock`
        (steps take turns on it in simulated-time order), a robot's wall clock."""
        ...

    def now(self) -> float:
        """The world's time in seconds: simulated time, or wall time for a real robot."""
        ...

    def adopt(self, step: PlanStep, observations: Sequence[Observation]) -> None:
        """``step`` was done by a skill that is not the world's own (a user's skill)
        and succeeded: a simulated world takes the action's declared effects into its
        truth, then ``observations`` (they win); a real world has changed by itself."""
        ...

    def sense(self, steps: Sequence[PlanStep]) -> list[Observation]:
        """What the robot can observe now of the atoms ``steps`` read or change."""
        ...

    @property
    def faults_injected(self) -> int | None:
        """Faults the world injected so far (None: it does not know, e.g. a robot)."""
        ...

    def goal_reached(self) -> bool:
        """Whether the task's goal holds in the world's truth (for reports and the study)."""
        ...

    def snapshot(self) -> dict[str, Any] | None:
        """What a checkpoint keeps of the world (JSON data); None: it cannot be saved
        (its state lives elsewhere, as a robot's does), so a run cannot be resumed."""
        ...

    def restore(self, data: dict[str, Any]) -> None:
        """Put back a :meth:`snapshot`."""
        ...

    def abandon_running(self) -> None:
        """After :meth:`restore` into a new process: the actions that were in progress
        stopped with the old one (a drive is back where it began)."""
        ...

    def figures(self) -> dict[str, Any]:
        """The world's numbers for a run's report (``sim_time_s``, faults, ...)."""
        ...
