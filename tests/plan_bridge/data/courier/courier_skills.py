"""The courier's own skills, named by the skill maps of the tests (which copy this
folder to a temporary one and write a ``skills.toml`` next to this file)."""

from __future__ import annotations

from pathlib import Path

import smach

#: Where :class:`Drive` writes what it did (next to this module).
LOG = Path(__file__).with_name("skills.log")
#: Not a factory: a map naming it is refused.
SPEED = 0.5


class Drive(smach.State):
    """Drives ``robot`` to ``to``; reports where the robot is afterwards."""

    def __init__(self, robot: str, to: str) -> None:
        super().__init__(outcomes=["arrived", "blocked", "preempted"], output_keys=["observations"])
        self.robot = robot
        self.to = to

    def execute(self, ud: smach.UserData) -> str:
        with LOG.open("a", encoding="utf-8") as log:
            log.write(f"drive {self.robot} {self.to}\n")
        ud.observations = {f"(robot-at {self.robot} {self.to})": True}
        return "arrived"


class Grab(smach.State):
    """Succeeds at once; keeps the arguments its factory was given."""

    def __init__(self, *received: object) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])
        self.received = received

    def execute(self, ud: smach.UserData) -> str:
        return "succeeded"


def make_gentle_grab(robot: str, parcel: str, room: str) -> smach.State:
    """Another way to grab: takes exactly the action's three arguments."""
    return Grab("gentle", robot, parcel, room)
