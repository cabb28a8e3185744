"""The simulated home of the fetch_drink mission: true state, geometry and faults.

The world holds the true PDDL facts (what the planner's model would say if it knew
everything) plus what PDDL leaves out: corridor lengths and which corridors are
really blocked. Faults are drawn from the seeded ``rng`` and scale with
``fail_rate`` (0 means none); each is recorded with :meth:`inject`:

=====================  ======================================  ====================
fault                  when it is drawn                        probability
=====================  ======================================  ====================
drink-misplaced        setup, per drink (on another shelf)     3 x fail_rate
corridor-blocked       setup, per corridor (stays blocked)     1.5 x fail_rate
corridor-congested     per drive attempt (a person; moves on)  1 x fail_rate
handle-slip            per fridge-handle grasp                 1 x fail_rate
fridge-stuck           per pull on the fridge door             1.5 x fail_rate
grasp-slip             per grasp of a drink                    2 x fail_rate
door-rebound           per push to close the fridge            1 x fail_rate
=====================  ======================================  ====================

A persistent blockage never disconnects the home (the mission stays solvable), so
success rates measure recovery, not bad luck. Simulated durations advance
``sim_time``; nothing sleeps.
"""

from __future__ import annotations

import zlib
from collections import deque
from collections.abc import Iterable

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.skills.kit import shortest_route

__all__ = ["FetchDrinkWorld"]

Corridor = frozenset[str]

#: Fault probabilities per unit of fail_rate (see the module docstring).
FAULT_SCALE = {
    "drink-misplaced": 3.0,
    "corridor-blocked": 1.5,
    "corridor-congested": 1.0,
    "handle-slip": 1.0,
    "fridge-stuck": 1.5,
    "grasp-slip": 2.0,
    "door-rebound": 1.0,
}

#: World variants for studies: "unanticipated" moves every person to another room
#: before the robot arrives (nobody told the robot, and the scripted author did not
#: foresee it).
VARIANTS = ("", "unanticipated")

DRIVE_SPEED = 0.6  # m/s, the PR2's indoor cruising speed
CONGESTION_WAIT = 5.0  # s a person standing in a corridor takes to move on


class FetchDrinkWorld(SimulatedWorld):
    """A home with a fridge: places joined by corridors, drinks on shelves."""

    # Declared once: snapshot() saves every `state` attribute (see SimulatedWorld).
    state = ("blocked",)
    constant = ("corridors",)

    fault_scale = FAULT_SCALE
    variants = VARIANTS

    def __init__(
        self, task: PlanningTask, *, seed: int | None = 0, fail_rate: float = 0.0, variant: str = ""
    ) -> None:
        super().__init__(task, seed=seed, fail_rate=fail_rate, variant=variant)
        self.corridors: dict[Corridor, float] = {}
        for fact in task.initial_facts:
            if fact[0] == "connected":
                self.corridors[frozenset(fact[1:])] = corridor_length(fact[1], fact[2])
        self.blocked: set[Corridor] = set()
        self._misplace_drinks()
        self._block_corridors()
        if variant == "unanticipated":
            self._move_people()

    # -- faults decided when the world is made ------------------------------------------
    def _misplace_drinks(self) -> None:
        for fact in sorted(f for f in self._facts if f[0] == "on"):
            drink, shelf = fact[1], fact[2]
            others = [s for s in self.shelves_of(self.fridge_of(shelf)) if s != shelf]
            if others and self.chance("drink-misplaced"):
                actual = self.rng.choice(others)
                self._facts.discard(fact)
                self._facts.add(("on", drink, actual))
                self.inject("drink-misplaced", "setup", f"{drink} is on {actual}, not on {shelf}")

    def _block_corridors(self) -> None:
        for corridor in sorted(self.corridors, key=sorted):
            if not self.chance("corridor-blocked"):
                continue
            if not self._connected_without(self.blocked | {corridor}):
                continue  # keep the home connected: the mission must stay solvable
            self.blocked.add(corridor)
            a, b = sorted(corridor)
            self._facts -= {("clear", a, b), ("clear", b, a)}
            self.inject("corridor-blocked", "setup", f"a box blocks the corridor {a} - {b}")

    def _move_people(self) -> None:
        kitchens = {f[2] for f in self._facts if f[0] == "fridge-in"}
        for fact in sorted(f for f in self._facts if f[0] == "person-at"):
            person, place = fact[1], fact[2]
            elsewhere = sorted(p for p in self.neighbours(place) if p not in kitchens)
            if not elsewhere:
                continue
            moved = self.rng.choice(elsewhere)
            self._facts.discard(fact)
            self._facts.add(("person-at", person, moved))
            self.inject("person-moved", "setup", f"{person} went from {place} to {moved}")

    def where_is(self, person: str) -> str | None:
        """Where ``person`` really is (they answer when the robot calls them)."""
        return next((f[2] for f in self._facts if f[0] == "person-at" and f[1] == person), None)

    def _connected_without(self, blocked: set[Corridor]) -> bool:
        places = {p for c in self.corridors for p in c}
        if not places:
            return True
        start = min(places)
        seen = {start}
        queue = deque([start])
        while queue:
            here = queue.popleft()
            for there in self.neighbours(here, blocked):
                if there not in seen:
                    seen.add(there)
                    queue.append(there)
        return seen == places

    # -- queries -------------------------------------------------------------------------
    def neighbours(self, place: str, avoid: Iterable[Corridor] = ()) -> list[str]:
        avoided = set(avoid)
        return sorted(
            next(iter(c - {place}))
            for c in self.corridors
            if place in c and c not in avoided and len(c) == 2
        )

    def route(self, start: str, goal: str, avoid: Iterable[Corridor] = ()) -> list[str] | None:
        """The shortest route (by corridor length) on the floor plan, blocked corridors
        included (the plan does not show them), avoiding the corridors ``avoid``; or None."""
        avoided = set(avoid)
        return shortest_route(
            start,
            goal,
            lambda here: (
                (there, self.corridors[frozenset((here, there))])
                for there in self.neighbours(here, avoided)
            ),
        )

    def shelves_of(self, fridge: str) -> list[str]:
        return sorted(
            f[1] for f in self.task.initial_facts if f[0] == "shelf-of" and f[2] == fridge
        )

    def fridge_of(self, shelf: str) -> str:
        return next(f[2] for f in self.task.initial_facts if f[0] == "shelf-of" and f[1] == shelf)

    def robot_place(self, robot: str) -> str:
        with self._lock:
            return next(f[2] for f in self._facts if f[0] == "at" and f[1] == robot)

    def _elapse(self, seconds: float) -> None:
        self.sim_time += seconds

    def _move_fact(self, remove: Fact | None, add: Fact | None) -> None:
        with self._lock:
            if remove is not None:
                self._facts.discard(remove)
            if add is not None:
                self._facts.add(add)

    # -- actions the skills call ---------------------------------------------------------
    def drive(self, robot: str, origin: str, destination: str) -> str:
        """Drive one corridor: ``arrived``; or, back at ``origin``, ``congested`` (a person
        is in the way: the laser sees the obstacle move) or ``blocked`` (a static obstacle)."""
        corridor = frozenset((origin, destination))
        if corridor not in self.corridors or self.robot_place(robot) != origin:
            return "blocked"
        length = self.corridors[corridor]
        self.actions_run += 1
        if corridor in self.blocked:
            # The robot sees the box halfway along and returns to where it started.
            self._elapse(length / DRIVE_SPEED)
            return "blocked"
        if self.chance("corridor-congested"):
            self.inject(
                "corridor-congested", f"drive {origin} {destination}", "a person is in the way"
            )
            self._elapse(length / (2 * DRIVE_SPEED))
            return "congested"
        self._elapse(length / DRIVE_SPEED)
        self._move_fact(("at", robot, origin), ("at", robot, destination))
        return "arrived"

    def wait(self, seconds: float) -> None:
        self._elapse(seconds)

    def grasp_fridge_handle(self, fridge: str) -> bool:
        self._elapse(4.0)
        if self.chance("handle-slip"):
            self.inject("handle-slip", f"open {fridge}", "the gripper slid off the handle")
            return False
        return True

    def pull_fridge_door(self, fridge: str) -> bool:
        """Pull the door open; the magnetic seal sometimes holds it shut."""
        self._elapse(3.0)
        if self.chance("fridge-stuck"):
            self.inject("fridge-stuck", f"open {fridge}", "the door seal held")
            return False
        self._move_fact(("fridge-closed", fridge), ("fridge-open", fridge))
        return True

    def push_fridge_door(self, fridge: str) -> bool:
        """Push the door shut; it sometimes bounces back open."""
        self._elapse(3.0)
        if self.chance("door-rebound"):
            self.inject("door-rebound", f"close {fridge}", "the door bounced back open")
            return False
        self._move_fact(("fridge-open", fridge), ("fridge-closed", fridge))
        return True

    def look_for(self, drink: str, fridge: str) -> str | None:
        """The shelf of ``fridge`` the camera sees ``drink`` on (None if not there or shut)."""
        self._elapse(2.0)
        if not self.holds("fridge-open", fridge):
            return None
        shelves = set(self.shelves_of(fridge))
        with self._lock:
            return next(
                (f[2] for f in self._facts if f[0] == "on" and f[1] == drink and f[2] in shelves),
                None,
            )

    def grasp(self, robot: str, drink: str, shelf: str) -> bool:
        """Close the gripper on the drink and lift; it may slip back onto the shelf."""
        self._elapse(6.0)
        if not self.holds("on", drink, shelf) or not self.holds("hand-empty", robot):
            return False
        if self.chance("grasp-slip"):
            self.inject("grasp-slip", f"pick {drink}", f"{drink} slipped back onto {shelf}")
            return False
        with self._lock:
            self._facts -= {("on", drink, shelf), ("hand-empty", robot)}
            self._facts.add(("holding", robot, drink))
        return True

    def hand_over(self, robot: str, drink: str, person: str) -> bool:
        """Offer the drink; the person takes it if they are where the robot is."""
        self._elapse(5.0)
        place = self.robot_place(robot)
        if not self.holds("holding", robot, drink) or not self.holds("person-at", person, place):
            return False
        with self._lock:
            self._facts.discard(("holding", robot, drink))
            self._facts |= {("hand-empty", robot), ("served", person, drink)}
        return True


def corridor_length(a: str, b: str) -> float:
    """A fixed length (3 to 8 m) per corridor, the same in every run of a problem."""
    key = "|".join(sorted((a, b))).encode()
    return 3.0 + zlib.crc32(key) % 6
