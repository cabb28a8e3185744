"""The simulated building with two robots: the true state and its faults.

Both robots act at the same time (their plan steps run in a smach.Concurrence), so
every method takes the world's lock. Determinism for a given seed does not depend
on how the two threads interleave:

- each robot draws its faults from its own generator, seeded from the run's seed
  and the robot's name, and a robot's steps never run concurrently with each other
  (they all touch its position or its gripper), so each generator is used in a
  fixed order;
- the door that will be found blocked (at most one per run) is chosen when the
  world is made;
- each robot keeps its own simulated clock; :attr:`sim_time` is the later of the
  two (the mission's makespan) and faults are stamped with the robot's clock;
- every activity of a robot also takes its time on the world's shared
  :attr:`clock`, on which the steps of one plan layer take turns (in simulated-time
  order, ties broken by step index): what the two robots see of each other (a door
  found blocked, the belief their observations update) comes in one order.

Faults (rates scale with ``fail_rate``; 0 means none), each recorded with
:meth:`inject`:

- ``door-blocked``: a door is closed for the whole run (found when a robot tries it),
- ``nav-stalled``: a person stands in the way; the drive gives up this attempt,
- ``grasp-slip``: the item slips back onto the shelf,
- ``item-dropped``: the carried item falls off while the robot leaves a room,
- ``release-stuck``: the gripper does not open above the desk.
"""

from __future__ import annotations

import random

from plan_bridge.execution.simulation import Fault, SimulatedWorld
from plan_bridge.pddl.task import PlanningTask

__all__ = ["DeliveryWorld"]

#: Simulated seconds of the robots' activities.
DURATIONS = {
    "door-check": 1.0,
    "drive": 12.0,
    "stalled": 5.0,
    "detect": 1.5,
    "grasp": 2.5,
    "verify": 0.5,
    "release": 2.0,
}
#: Base probabilities of the faults at fail_rate 1 (they scale linearly with it).
FAULT_SCALE = {
    "door-blocked": 2.0,
    "nav-stalled": 1.0,
    "grasp-slip": 1.0,
    "item-dropped": 0.4,
    "release-stuck": 0.5,
}
#: Doors that can be found blocked (the storerooms' doors always open: without them
#: the mission is impossible).
BLOCKABLE = ("office", "lab", "hall-west", "hall-east", "corridor")


class DeliveryWorld(SimulatedWorld):
    """The true state of the two-robot delivery mission, with seeded faults."""

    # Declared once: snapshot() saves every `state` attribute (see SimulatedWorld).
    state = ("_clock", "_found_blocked", "_rngs", "blocked_door")
    constant = ("robots",)

    fault_scale = FAULT_SCALE

    def __init__(self, task: PlanningTask, *, seed: int | None = 0, fail_rate: float = 0.0) -> None:
        super().__init__(task, seed=seed, fail_rate=fail_rate)
        self.robots = tuple(sorted(task.objects_of_type("robot")))
        self._rngs = {robot: random.Random(f"{seed}:{robot}") for robot in self.robots}
        self._clock = dict.fromkeys(self.robots, 0.0)
        self._found_blocked: set[tuple[str, frozenset[str]]] = set()
        doors = sorted(
            {
                frozenset(f[1:])
                for f in self._facts
                if f[0] == "connected" and set(f[1:]) <= set(BLOCKABLE)
            },
            key=sorted,
        )
        self.blocked_door: frozenset[str] | None = None
        if doors and self.chance("door-blocked"):
            self.blocked_door = self.rng.choice(doors)

    # -- time and faults --------------------------------------------------------------------
    @property
    def sim_time(self) -> float:
        """The mission's makespan: the later of the robots' clocks."""
        clocks: dict[str, float] = self.__dict__.get("_clock", {})
        return max(clocks.values(), default=0.0)

    @sim_time.setter
    def sim_time(self, value: float) -> None:
        # The base class sets the time to 0 in __init__; the robots' clocks start at 0.
        pass

    def robot_time(self, robot: str) -> float:
        """The simulated seconds ``robot`` has spent so far (its own clock)."""
        with self._lock:
            return self._clock[robot]

    def _spend(self, robot: str, activity: str) -> None:
        self._clock[robot] += DURATIONS[activity]
        self.elapse(DURATIONS[activity])  # the shared clock: turns, pacing

    def inject(
        self, kind: str, action: str, detail: str = "", *, robot: str | None = None
    ) -> Fault:
        """Record a fault; a robot's fault is stamped with that robot's own clock.

        (The shared makespan would depend on how far the other robot has got, which
        depends on thread timing.)
        """
        if robot is None:
            return super().inject(kind, action, detail)
        fault = Fault(self._clock[robot], kind, action, detail)
        self.faults.append(fault)
        return fault

    def faults_of(self, robot: str) -> list[Fault]:
        with self._lock:
            return [f for f in self.faults if f.action.split(" ")[1:2] == [robot]]

    # -- sensors ----------------------------------------------------------------------------
    def location(self, robot: str) -> str | None:
        with self._lock:
            return next((f[2] for f in self._facts if f[0] == "at" and f[1] == robot), None)

    def held_by(self, robot: str) -> str | None:
        """What the gripper holds (its force sensor), or None."""
        with self._lock:
            self._spend(robot, "verify")
            return next((f[2] for f in self._facts if f[0] == "holding" and f[1] == robot), None)

    def door_open(self, robot: str, source: str, target: str) -> bool:
        """Look at the door ahead (laser and camera)."""
        with self._lock:
            self._spend(robot, "door-check")
            door = frozenset((source, target))
            if door != self.blocked_door:
                return True
            if (robot, door) not in self._found_blocked:
                self._found_blocked.add((robot, door))
                self.inject(
                    "door-blocked",
                    f"(move {robot} {source} {target})",
                    f"{source} <-> {target}",
                    robot=robot,
                )
            return False

    def sees(self, robot: str, item: str) -> bool:
        """Is ``item`` on the shelves of the robot's room?"""
        with self._lock:
            self._spend(robot, "detect")
            here = next((f[2] for f in self._facts if f[0] == "at" and f[1] == robot), "")
            return ("item-at", item, here) in self._facts

    # -- actions ----------------------------------------------------------------------------
    def drive(self, robot: str, source: str, target: str) -> str:
        """Drive through the door: ``arrived``, ``stalled`` (try again) or ``failed``."""
        with self._lock:
            self.actions_run += 1
            if ("at", robot, source) not in self._facts or (
                "connected",
                source,
                target,
            ) not in self._facts:
                return "failed"
            if frozenset((source, target)) == self.blocked_door:
                return "failed"
            rng = self._rngs[robot]
            if self.chance("nav-stalled", rng):
                self._spend(robot, "stalled")
                self.inject(
                    "nav-stalled",
                    f"(move {robot} {source} {target})",
                    "a person blocks the way",
                    robot=robot,
                )
                return "stalled"
            self._spend(robot, "drive")
            held = next((f[2] for f in self._facts if f[0] == "holding" and f[1] == robot), None)
            if held is not None and self.chance("item-dropped", rng):
                self._facts.discard(("holding", robot, held))
                self._facts.add(("hand-empty", robot))
                self._facts.add(("item-at", held, source))
                self.inject(
                    "item-dropped",
                    f"(move {robot} {source} {target})",
                    f"{held} fell in {source}",
                    robot=robot,
                )
            self._facts.discard(("at", robot, source))
            self._facts.add(("at", robot, target))
            return "arrived"

    def grasp(self, robot: str, item: str) -> None:
        with self._lock:
            self.actions_run += 1
            self._spend(robot, "grasp")
            here = next((f[2] for f in self._facts if f[0] == "at" and f[1] == robot), "")
            if ("item-at", item, here) not in self._facts or (
                "hand-empty",
                robot,
            ) not in self._facts:
                return
            if self.chance("grasp-slip", self._rngs[robot]):
                self.inject(
                    "grasp-slip", f"(pick {robot} {item} {here})", "back on the shelf", robot=robot
                )
                return
            self._facts.discard(("item-at", item, here))
            self._facts.discard(("hand-empty", robot))
            self._facts.add(("holding", robot, item))

    def release(self, robot: str, item: str) -> None:
        with self._lock:
            self.actions_run += 1
            self._spend(robot, "release")
            here = next((f[2] for f in self._facts if f[0] == "at" and f[1] == robot), "")
            if ("holding", robot, item) not in self._facts:
                return
            if self.chance("release-stuck", self._rngs[robot]):
                self.inject(
                    "release-stuck",
                    f"(drop {robot} {item} {here})",
                    "the gripper stays shut",
                    robot=robot,
                )
                return
            self._facts.discard(("holding", robot, item))
            self._facts.add(("hand-empty", robot))
            self._facts.add(("item-at", item, here))
