"""The simulated building of the door_opening mission: true door states and faults.

The world holds the true PDDL facts; the planner's model believes every door is
unlocked, the world knows better. Faults are drawn from the seeded ``rng``, scale
with ``fail_rate`` (0 means none) and are recorded with :meth:`inject`:

=============  ==============================================  ===================
fault          when it is drawn                                probability
=============  ==============================================  ===================
door-locked    setup, per door (stays locked)                  1.5 x fail_rate
handle-slip    per grasp of a door handle                      1 x fail_rate
door-stuck     per push on an unlocked door (swollen frame)    2 x fail_rate
door-swung     per pass through an open door (door closer)     1 x fail_rate
=============  ==============================================  ===================

Locking never cuts the start off from the goal, so the mission stays solvable and
success rates measure recovery. Simulated durations advance ``sim_time``.
"""

from __future__ import annotations

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import fewest_hops

__all__ = ["DoorWorld", "Joint"]

FAULT_SCALE = {
    "door-locked": 1.5,
    "handle-slip": 1.0,
    "door-stuck": 2.0,
    "door-swung": 1.0,
}

#: World variants for studies: "unanticipated" also locks a door on the shortest route
#: AND one on the detour the scripted author hard-coded (the goal stays reachable).
VARIANTS = ("", "unanticipated")

ROOM_CROSSING = 8.0  # s to cross a room to the next door or passage

Joint = tuple[str, str, str | None]
"""(from room, to room, door or None for a passage)."""


class DoorWorld(SimulatedWorld):
    """Rooms joined by doors and passages; some doors are really locked."""

    # Declared once: snapshot() saves every `state` attribute (see SimulatedWorld).
    state = ("locked",)
    constant = ("doors", "passages", "start", "goal_rooms")

    fault_scale = FAULT_SCALE
    variants = VARIANTS

    def __init__(
        self, task: PlanningTask, *, seed: int | None = 0, fail_rate: float = 0.0, variant: str = ""
    ) -> None:
        super().__init__(task, seed=seed, fail_rate=fail_rate, variant=variant)
        facts = task.initial_facts
        self.doors: dict[str, tuple[str, str]] = {}
        for f in sorted(facts):
            if f[0] == "door-between" and f[1] not in self.doors:
                self.doors[f[1]] = (f[2], f[3])
        self.passages = {frozenset(f[1:]) for f in facts if f[0] == "passage"}
        self.start = next(f[2] for f in facts if f[0] == "at")
        self.goal_rooms = [g[2] for g in task.goal_facts if g[0] == "at"]
        self.locked: set[str] = set()
        self._lock_doors()
        if variant == "unanticipated":
            self._lock_route_and_detour()

    def _lock_doors(self) -> None:
        for door in sorted(self.doors):
            if not self.chance("door-locked"):
                continue
            if not all(
                self.reachable(self.start, g, self.locked | {door}) for g in self.goal_rooms
            ):
                continue  # keep a way to the goal: the mission must stay solvable
            self.locked.add(door)
            self._facts.discard(("unlocked", door))
            self.inject("door-locked", "setup", f"{door} is locked")

    def route(self, avoid_doors: set[str]) -> list[str] | None:
        """Doors on the route with the fewest joints to the first goal room, or None."""
        joints = self.joints(self.start, self.goal_rooms[0], avoid_doors)
        return None if joints is None else [door for _, _, door in joints if door]

    def _lock_route_and_detour(self) -> None:
        """A second locked door, on the detour too: what the scripted author did not expect."""
        route = self.route(set()) or []
        detour = self.route(set(route)) or []
        for doors in (route, detour):
            for door in reversed(doors):
                trial = self.locked | {door}
                if door not in self.locked and all(
                    self.reachable(self.start, g, trial) for g in self.goal_rooms
                ):
                    self.locked.add(door)
                    self._facts.discard(("unlocked", door))
                    self.inject("door-locked", "setup", f"{door} is locked (unanticipated)")
                    break

    def reachable(self, start: str, goal: str, locked: set[str]) -> bool:
        return self.joints(start, goal, locked) is not None

    def joints(
        self, start: str, goal: str, avoid_doors: set[str] | None = None
    ) -> list[Joint] | None:
        """The route with the fewest joints on the building's plan, or None."""
        return fewest_hops(start, goal, lambda room: self.exits(room, avoid_doors))

    def exits(self, room: str, avoid_doors: set[str] | None = None) -> list[tuple[str, str | None]]:
        """(neighbouring room, door or None for a passage), on the building's plan."""
        avoid = avoid_doors or set()
        out: list[tuple[str, str | None]] = [
            (next(iter(p - {room})), None) for p in self.passages if room in p
        ]
        for door, (a, b) in self.doors.items():
            if door not in avoid and room in (a, b):
                out.append((b if room == a else a, door))
        return sorted(out, key=lambda e: (e[0], e[1] or ""))

    # -- queries -------------------------------------------------------------------------
    def robot_room(self, robot: str) -> str:
        with self._lock:
            return next(f[2] for f in self._facts if f[0] == "at" and f[1] == robot)

    def _set(self, fact: tuple[str, ...], truth: bool) -> None:
        with self._lock:
            if truth:
                self._facts.add(fact)
            else:
                self._facts.discard(fact)

    # -- actions the skills call ---------------------------------------------------------
    def cross(self, robot: str, origin: str, destination: str) -> bool:
        """Drive through an open passage."""
        self.sim_time += ROOM_CROSSING
        self.actions_run += 1
        if frozenset((origin, destination)) not in self.passages:
            return False
        if self.robot_room(robot) != origin:
            return False
        self._set(("at", robot, origin), False)
        self._set(("at", robot, destination), True)
        return True

    def find_handle(self, door: str) -> bool:
        self.sim_time += 2.0
        return door in self.doors

    def grasp_handle(self, door: str) -> bool:
        self.sim_time += 3.0
        if self.chance("handle-slip"):
            self.inject("handle-slip", f"open {door}", "the gripper slid off the handle")
            return False
        return True

    def turn_handle(self, door: str) -> bool:
        """Turn the handle; False when the latch does not retract (the door is locked)."""
        self.sim_time += 2.0
        return door not in self.locked

    def push_door(self, door: str) -> bool:
        """Push the door open; a stuck door does not move this time (push harder)."""
        self.sim_time += 4.0
        self.actions_run += 1
        if door in self.locked:
            return False
        if self.chance("door-stuck"):
            self.inject("door-stuck", f"open {door}", "the door is stuck in its frame")
            return False
        self._set(("door-closed", door), False)
        self._set(("door-open", door), True)
        return True

    def release_handle(self, door: str) -> None:
        self.sim_time += 1.0

    def pass_door(self, robot: str, door: str, origin: str, destination: str) -> bool:
        """Drive through the open door; its closer may swing it shut in front of the robot."""
        self.sim_time += ROOM_CROSSING
        self.actions_run += 1
        if not self.holds("door-open", door) or self.robot_room(robot) != origin:
            return False
        if origin not in self.doors[door] or destination not in self.doors[door]:
            return False
        if self.chance("door-swung"):
            self.inject("door-swung", f"pass {door}", "the door closer swung the door shut")
            self._set(("door-open", door), False)
            self._set(("door-closed", door), True)
            return False
        self._set(("at", robot, origin), False)
        self._set(("at", robot, destination), True)
        return True
