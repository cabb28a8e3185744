"""The simulated floor of the recharge mission: rooms, items, a charger and a battery.

The world holds the true PDDL facts and the battery's charge in percent. The
battery drains with every motion and manipulation; below :data:`LOW_THRESHOLD` the
power board raises LOW (facts ``battery-low`` instead of ``battery-ok``), tells its
subscribers (the battery monitors) and, to save the reserve for docking, the base
accepts only docking motions: an ordinary drive holds where it is until the monitor
preempts it, and the robot then stops at the nearer end of the corridor.

Faults are drawn from the seeded ``rng``, scale with ``fail_rate`` (0 means none)
and are recorded with :meth:`inject`:

======================  ============================================  =================
fault                   when it is drawn                              probability
======================  ============================================  =================
battery-not-full        setup: the robot starts at 31-40 % charge     5 x fail_rate
load-spike              per 2 m of driving: +3 % drain                0.5 x fail_rate
grasp-slip              per grasp of an item                          1 x fail_rate
plug-misaligned         per attempt to insert the plug                2 x fail_rate
======================  ============================================  =================

Without faults the battery lasts the whole mission (no recharge is needed).
Simulated durations advance ``sim_time``; nothing sleeps.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from dataclasses import dataclass

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import shortest_route

__all__ = ["LOW_THRESHOLD", "RechargeWorld"]

FAULT_SCALE = {
    "battery-not-full": 5.0,
    "load-spike": 0.5,
    "grasp-slip": 1.0,
    "plug-misaligned": 2.0,
}

LOW_THRESHOLD = 30.0  # % below which the power board raises LOW
SEGMENT = 2.0  # m driven per control step
SPEED = 0.6  # m/s
DRAIN_PER_M = 0.25  # % per m at cruising power
DOCKING_DRAIN_PER_M = 0.15  # % per m in the slow, low-power docking mode
LOAD_SPIKE = 3.0  # % lost to a load spike (a ramp, a heavy door, a cold cell)
CHARGE_RATE = 0.5  # % per s on the charger


@dataclass
class Transit:
    """A drive in progress along one corridor."""

    origin: str
    destination: str
    length: float
    driven: float = 0.0
    docking: bool = False


class RechargeWorld(SimulatedWorld):
    """Rooms joined by corridors, items to carry, a charger and a draining battery."""

    # Declared once: snapshot() saves every `state` attribute (see SimulatedWorld).
    state = ("battery", "recharges", "_transit")
    constant = ("corridors", "chargers")
    wiring = ("_low_listeners",)

    fault_scale = FAULT_SCALE

    def __init__(self, task: PlanningTask, *, seed: int | None = 0, fail_rate: float = 0.0) -> None:
        super().__init__(task, seed=seed, fail_rate=fail_rate)
        self.corridors: dict[frozenset[str], float] = {
            frozenset(f[1:]): corridor_length(f[1], f[2])
            for f in task.initial_facts
            if f[0] == "connected"
        }
        self.chargers = sorted(f[1] for f in task.initial_facts if f[0] == "charger-at")
        self.battery = 100.0
        self.recharges = 0
        self._transit: dict[str, Transit] = {}
        self._low_listeners: list[Callable[[], None]] = []
        if self.chance("battery-not-full"):
            self.battery = 31.0 + self.rng.random() * 9.0
            self.inject("battery-not-full", "setup", f"the battery starts at {self.battery:.0f} %")

    # -- the power board ---------------------------------------------------------------
    def battery_low(self) -> bool:
        return self.battery < LOW_THRESHOLD

    def on_battery_low(self, callback: Callable[[], None]) -> Callable[[], None]:
        """Call ``callback`` (from the draining thread) when LOW is raised; at once if it
        is raised already. Returns the function that unsubscribes."""
        with self._lock:
            self._low_listeners.append(callback)
        if self.battery_low():
            callback()

        def unsubscribe() -> None:
            with self._lock:
                if callback in self._low_listeners:
                    self._low_listeners.remove(callback)

        return unsubscribe

    def _drain(self, percent: float) -> None:
        was_low = self.battery_low()
        self.battery = max(0.0, self.battery - percent)
        if self.battery_low() and not was_low:
            robot = self.robot
            with self._lock:
                self._facts.discard(("battery-ok", robot))
                self._facts.add(("battery-low", robot))
                listeners = list(self._low_listeners)
            for listener in listeners:
                listener()

    @property
    def robot(self) -> str:
        return next(f[1] for f in self.task.initial_facts if f[0] == "at")

    # -- queries -------------------------------------------------------------------------
    def room_of(self, robot: str) -> str:
        with self._lock:
            return next(f[2] for f in self._facts if f[0] == "at" and f[1] == robot)

    def route(self, start: str, goal: str) -> list[str] | None:
        """The shortest route (by length) on the floor plan, or None."""
        return shortest_route(
            start,
            goal,
            lambda here: (
                (next(iter(corridor - {here})), length)
                for corridor, length in self.corridors.items()
                if here in corridor
            ),
        )

    def _move(self, robot: str, origin: str, destination: str) -> None:
        with self._lock:
            self._facts.discard(("at", robot, origin))
            self._facts.add(("at", robot, destination))

    # -- driving -------------------------------------------------------------------------
    def start_drive(
        self, robot: str, origin: str, destination: str, *, docking: bool = False
    ) -> bool:
        """Begin driving one corridor; False if there is none or the robot is elsewhere."""
        corridor = frozenset((origin, destination))
        if corridor not in self.corridors or self.room_of(robot) != origin:
            return False
        if not self.holds("unplugged", robot):
            return False
        self.actions_run += 1
        self._transit[robot] = Transit(
            origin, destination, self.corridors[corridor], docking=docking
        )
        return True

    def drive_step(self, robot: str) -> str:
        """Drive one segment: ``moving``, ``arrived``, ``held`` (LOW and not docking: the
        base waits for the supervisor) or ``dead`` (the battery is empty)."""
        transit = self._transit[robot]
        if self.battery <= 0.0:
            return "dead"
        if self.battery_low() and not transit.docking:
            return "held"
        step = min(SEGMENT, transit.length - transit.driven)
        transit.driven += step
        self.sim_time += step / SPEED
        per_m = DOCKING_DRAIN_PER_M if transit.docking else DRAIN_PER_M
        self._drain(step * per_m)
        if self.chance("load-spike"):
            self.inject("load-spike", f"drive {transit.origin} {transit.destination}", "+3 % drain")
            self._drain(LOAD_SPIKE)
        if transit.driven >= transit.length:
            del self._transit[robot]
            self._move(robot, transit.origin, transit.destination)
            return "arrived"
        return "moving"

    def stop_drive(self, robot: str) -> str:
        """Stop in the corridor and return to its nearer end; the room the robot is in."""
        transit = self._transit.pop(robot, None)
        if transit is None:
            return self.room_of(robot)
        if transit.driven > transit.length / 2:
            self.sim_time += (transit.length - transit.driven) / SPEED
            self._move(robot, transit.origin, transit.destination)
            return transit.destination
        self.sim_time += transit.driven / SPEED
        return transit.origin

    # -- manipulation and charging -------------------------------------------------------
    def grasp(self, robot: str, item: str, room: str) -> bool:
        self.sim_time += 6.0
        self._drain(1.0)
        if not self.holds("item-at", item, room) or not self.holds("hand-empty", robot):
            return False
        if self.room_of(robot) != room:
            return False
        if self.chance("grasp-slip"):
            self.inject("grasp-slip", f"pick {item}", f"{item} slipped out of the gripper")
            return False
        with self._lock:
            self._facts -= {("item-at", item, room), ("hand-empty", robot)}
            self._facts.add(("holding", robot, item))
        return True

    def put_down(self, robot: str, item: str) -> bool:
        self.sim_time += 4.0
        self._drain(0.5)
        if not self.holds("holding", robot, item):
            return False
        room = self.room_of(robot)
        with self._lock:
            self._facts.discard(("holding", robot, item))
            self._facts |= {("item-at", item, room), ("hand-empty", robot)}
        return True

    def insert_plug(self, robot: str) -> bool:
        """Align with the wall socket and push the plug in; it may miss the socket."""
        self.sim_time += 5.0
        room = self.room_of(robot)
        if room not in self.chargers or not self.holds("unplugged", robot):
            return False
        if self.chance("plug-misaligned"):
            self.inject("plug-misaligned", f"plug-in {room}", "the plug missed the socket")
            return False
        with self._lock:
            self._facts.discard(("unplugged", robot))
            self._facts.add(("plugged", robot))
        return True

    def charging_current(self, robot: str) -> bool:
        return self.holds("plugged", robot)

    def charge(self, robot: str) -> bool:
        """Charge to full (simulated time only); False if not plugged in."""
        if not self.holds("plugged", robot):
            return False
        self.sim_time += (100.0 - self.battery) / CHARGE_RATE
        self.battery = 100.0
        self.recharges += 1
        with self._lock:
            self._facts.discard(("battery-low", robot))
            self._facts.add(("battery-ok", robot))
        return True

    def pull_plug(self, robot: str) -> bool:
        self.sim_time += 3.0
        if not self.holds("plugged", robot):
            return self.holds("unplugged", robot)
        with self._lock:
            self._facts.discard(("plugged", robot))
            self._facts.add(("unplugged", robot))
        return True


def corridor_length(a: str, b: str) -> float:
    """A fixed length (5 to 12 m) per corridor, the same in every run of a problem."""
    key = "|".join(sorted((a, b))).encode()
    return 5.0 + zlib.crc32(key) % 8
