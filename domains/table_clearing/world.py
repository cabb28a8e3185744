"""The simulated dining room, corridors and kitchen: the true state and its faults.

The world keeps the true PDDL facts (``_facts``) and changes them only through the
small methods the skills call (look, grasp, release, drive, push). Every random
fault is drawn from the world's seeded generator, scaled by ``fail_rate`` (0 means
no faults at all), and recorded with :meth:`inject`:

- ``misplaced``: an object is not where the problem says; it lies in another zone
  of the table (decided when the world is made),
- ``occluded``: an object is hidden from the head camera for the first few looks,
- ``grasp-slip``: the object slips out of the gripper, back onto the table or down
  to the floor next to the robot,
- ``release-stuck``: the gripper does not let go above the cart,
- ``wheels-stalled``: a caster of the cart jams while pushing (backing up frees it),
- ``corridor-blocked``: a passage is blocked for the cart for the rest of the run
  (at most one per run, so the kitchen stays reachable).

Simulated time (:attr:`sim_time`) advances by the durations of what the robot does;
nothing sleeps for real.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import PlanningTask

__all__ = ["CartRun", "TableWorld"]

#: Simulated seconds of the robot's primitive activities.
DURATIONS = {
    "look": 1.5,
    "approach": 3.0,
    "grasp": 2.0,
    "verify": 0.5,
    "release": 2.0,
    "walk": 6.0,
    "push-segment": 5.0,
    "back-up": 4.0,
    "handle": 1.5,
}
#: A cart run is pushed in this many segments; the monitor checks after each.
PUSH_SEGMENTS = 4

#: Base probabilities of the faults at fail_rate 1 (they scale linearly with it).
FAULT_SCALE = {
    "misplaced": 0.5,
    "occluded": 1.0,
    "grasp-slip": 1.0,
    "release-stuck": 0.5,
    "wheels-stalled": 1.0,
    "corridor-blocked": 0.75,
}
#: Share of grasp slips where the object falls to the floor (the rest: back on the table).
FLOOR_SHARE = 0.35


@dataclass
class CartRun:
    """What the cart's wheel encoders and bumper report during one push."""

    source: str
    target: str
    segment: int = 0
    status: str = "moving"
    """moving, arrived, stalled (a wheel jams) or obstacle (the passage is blocked)."""
    stall_at: int | None = None
    obstacle_at: int | None = None
    changed: threading.Event = field(default_factory=threading.Event, repr=False, compare=False)
    """Set whenever the status changes, so that a monitor can wait for news."""


class TableWorld(SimulatedWorld):
    """The true state of the table-clearing mission, with seeded faults."""

    # Declared once: snapshot() saves every `state` attribute (see SimulatedWorld).
    state = ("_hidden", "_blocked", "_judged")
    constant = ("robots", "carts", "table_zones")

    fault_scale = FAULT_SCALE

    def __init__(self, task: PlanningTask, *, seed: int | None = 0, fail_rate: float = 0.0) -> None:
        super().__init__(task, seed=seed, fail_rate=fail_rate)
        self.robots = task.objects_of_type("robot")
        self.carts = task.objects_of_type("cart")
        self.table_zones = tuple(
            s for s in task.objects_of_type("spot") if not s.startswith("floor")
        )
        self._hidden: dict[str, int] = {}
        self._blocked: set[frozenset[str]] = set()
        self._judged: set[frozenset[str]] = set()
        for item in sorted(task.objects_of_type("item")):
            spot = self._spot_of(item)
            if spot in self.table_zones and self.chance("misplaced"):
                elsewhere = [z for z in self.table_zones if z != spot]
                truth = self.rng.choice(elsewhere)
                self._facts.discard(("item-at", item, spot))
                self._facts.add(("item-at", item, truth))
                self.inject("misplaced", "", f"{item} lies in {truth}, not in {spot}")
            if self.chance("occluded"):
                looks = self.rng.randint(1, 4)
                self._hidden[item] = looks
                self.inject("occluded", "", f"{item} is hidden for {looks} look(s)")

    # -- helpers (call with the lock held where they touch facts) ----------------------------
    def _spend(self, activity: str, times: int = 1) -> None:
        self.sim_time += DURATIONS[activity] * times

    def _spot_of(self, item: str) -> str | None:
        for fact in self._facts:
            if fact[0] == "item-at" and fact[1] == item:
                return fact[2]
        return None

    def _location_of(self, predicate: str, thing: str) -> str | None:
        for fact in self._facts:
            if fact[0] == predicate and fact[1] == thing:
                return fact[2]
        return None

    def _floor_near(self, location: str) -> str | None:
        for fact in self._facts:
            if fact[0] == "reaches" and fact[1] == location and fact[2].startswith("floor"):
                return fact[2]
        return None

    # -- what sensors report -----------------------------------------------------------------
    def robot_location(self, robot: str) -> str | None:
        with self._lock:
            return self._location_of("robot-at", robot)

    def cart_location(self, cart: str) -> str | None:
        with self._lock:
            return self._location_of("cart-at", cart)

    def held_by(self, robot: str) -> str | None:
        """What the gripper holds (its force sensor), or None."""
        with self._lock:
            self._spend("verify")
            for fact in self._facts:
                if fact[0] == "holding" and fact[1] == robot:
                    return fact[2]
            return None

    def look(self, robot: str, item: str) -> str | None:
        """Point the head camera at the table and the floor: the spot where ``item`` is seen.

        The camera sees the whole table and the floor beside the robot. An occluded
        object stays unseen for a few looks.
        """
        with self._lock:
            self._spend("look")
            self.actions_run += 1
            hidden = self._hidden.get(item, 0)
            if hidden > 0:
                self._hidden[item] = hidden - 1
                return None
            spot = self._spot_of(item)
            if spot is None:
                return None
            here = self._location_of("robot-at", robot)
            if spot in self.table_zones or spot == self._floor_near(here or ""):
                return spot
            return None

    def reachable(self, robot: str, spot: str) -> bool:
        with self._lock:
            here = self._location_of("robot-at", robot)
            return ("reaches", here or "", spot) in self._facts

    def is_on_cart(self, item: str, cart: str) -> bool:
        with self._lock:
            self._spend("verify")
            return ("on-cart", item, cart) in self._facts

    # -- arm ---------------------------------------------------------------------------------
    def approach(self, robot: str, spot: str) -> bool:
        """Move the arm to the pre-grasp pose above ``spot``; False if out of reach."""
        with self._lock:
            self._spend("approach")
            here = self._location_of("robot-at", robot)
            return ("reaches", here or "", spot) in self._facts

    def grasp(self, robot: str, item: str, spot: str) -> None:
        """Close the gripper on ``item`` at ``spot``; it may slip (to the table or floor)."""
        with self._lock:
            self._spend("grasp")
            here = self._location_of("robot-at", robot) or ""
            if (
                ("item-at", item, spot) not in self._facts
                or ("reaches", here, spot) not in self._facts
                or ("hand-empty", robot) not in self._facts
            ):
                return  # closes on air
            if self.chance("grasp-slip"):
                floor = self._floor_near(here)
                if floor is not None and self.rng.random() < FLOOR_SHARE:
                    self._facts.discard(("item-at", item, spot))
                    self._facts.add(("item-at", item, floor))
                    self.inject("grasp-slip", f"(pick {robot} {item})", f"{item} fell to {floor}")
                else:
                    self.inject(
                        "grasp-slip", f"(pick {robot} {item})", f"{item} fell back on {spot}"
                    )
                return
            self._facts.discard(("item-at", item, spot))
            self._facts.discard(("hand-empty", robot))
            self._facts.add(("holding", robot, item))

    def release_on_cart(self, robot: str, item: str, cart: str) -> None:
        """Open the gripper above the cart; the fingers may stick."""
        with self._lock:
            self._spend("release")
            here = self._location_of("robot-at", robot)
            if ("holding", robot, item) not in self._facts or (
                "cart-at",
                cart,
                here or "",
            ) not in self._facts:
                return
            if self.chance("release-stuck"):
                self.inject("release-stuck", f"(place {robot} {item})", "the gripper did not open")
                return
            self._facts.discard(("holding", robot, item))
            self._facts.add(("hand-empty", robot))
            self._facts.add(("on-cart", item, cart))

    # -- base --------------------------------------------------------------------------------
    def walk(self, robot: str, source: str, target: str) -> bool:
        """Drive the base (without the cart) to an adjacent location."""
        with self._lock:
            self._spend("walk")
            self.actions_run += 1
            if ("robot-at", robot, source) not in self._facts or (
                "adjacent",
                source,
                target,
            ) not in self._facts:
                return False
            self._facts.discard(("robot-at", robot, source))
            self._facts.add(("robot-at", robot, target))
            return True

    def grip_handle(self, robot: str, cart: str) -> bool:
        with self._lock:
            self._spend("handle")
            here = self._location_of("robot-at", robot)
            return (
                here is not None
                and ("cart-at", cart, here) in self._facts
                and ("hand-empty", robot) in self._facts
            )

    def start_push(self, robot: str, cart: str, source: str, target: str) -> CartRun:
        """Begin pushing the cart from ``source`` to ``target``: faults are decided here."""
        with self._lock:
            self.actions_run += 1
            run = CartRun(source, target)
            passage = frozenset((source, target))
            if ("passage", source, target) not in self._facts:
                run.status = "obstacle"
                return run
            # Only the corridors outside the dining room get blocked.
            corridor = not any(place.startswith("table") for place in passage)
            if passage not in self._judged and corridor and not self._blocked:
                self._judged.add(passage)
                if self.chance("corridor-blocked"):
                    self._blocked.add(passage)
                    self.inject(
                        "corridor-blocked",
                        f"(push-cart {robot} {cart} {source} {target})",
                        f"{source} <-> {target} is blocked for the cart",
                    )
            if passage in self._blocked:
                run.obstacle_at = 1 + self.rng.randrange(PUSH_SEGMENTS - 1)
            elif self.chance("wheels-stalled"):
                run.stall_at = 1 + self.rng.randrange(PUSH_SEGMENTS - 1)
                self.inject(
                    "wheels-stalled",
                    f"(push-cart {robot} {cart} {source} {target})",
                    f"a caster jams after segment {run.stall_at}",
                )
            return run

    def push_segment(self, robot: str, cart: str, run: CartRun) -> str:
        """Push one segment; returns the run's new status."""
        with self._lock:
            if run.status != "moving":
                return run.status
            if run.obstacle_at is not None and run.segment >= run.obstacle_at:
                run.status = "obstacle"
            elif run.stall_at is not None and run.segment >= run.stall_at:
                run.status = "stalled"
            else:
                self._spend("push-segment")
                run.segment += 1
                if run.segment >= PUSH_SEGMENTS:
                    for predicate, thing in (("robot-at", robot), ("cart-at", cart)):
                        self._facts.discard((predicate, thing, run.source))
                        self._facts.add((predicate, thing, run.target))
                    run.status = "arrived"
            run.changed.set()
            return run.status

    def back_up(self, run: CartRun) -> None:
        """Pull the cart back to where the run started (frees a jammed caster)."""
        with self._lock:
            self._spend("back-up")
            run.segment = 0
            run.stall_at = None
            run.status = "moving"

    def passage_clear(self, source: str, target: str) -> bool:
        """What the bumper and the laser tell about the passage ahead."""
        with self._lock:
            return frozenset((source, target)) not in self._blocked
