"""Building blocks for missions written by hand over the robosim skills.

The scripted baselines of the pyrobosim worlds (``domains/robosim_*/scripted.py``) are
SMACH machines their authors wrote without a planner. They drive the same skill
machines as the planned missions (:func:`~plan_bridge.robosim.skills.skill_for`) in
the same :class:`~plan_bridge.robosim.world.RobosimWorld`, with the recoveries a careful
author anticipates, built from these states:

* :class:`Drive` goes to a place leg by leg on the shortest way not known blocked
  (:func:`route`), tries each leg three times, opens a closed door it finds on its way
  (a hallway closed but not locked), and gives up on a hallway it finds locked or
  cannot open (``blocked``: the caller looks for another way);
* :class:`CheckBattery` says whether the battery covers the trip and the way from its
  end to a charger;
* :class:`Act` runs one action (pick, place, open, close, charge, detect), tried three
  times; opening what is open already is done at once;
* :func:`go_to` chains them: check the battery, charge first when it is low, drive,
  and look for another way when blocked; :func:`deliver` carries an object (go to it,
  open its location, pick, go to the target, place).

The machines share the userdata keys ``blocked`` (hallways known impassable) and
``legs`` (the legs driven, for reports).

For a stream of orders dispatched by hand (``domains/robosim_hospital/scripted.py``):
:func:`read_order_goal` reads an order's goal as the planned mission does,
:func:`deliveries_of` its deliveries, :func:`whereabouts` says where an object is now,
:class:`ClockSignal` lets a dispatcher and the robots' machines wait for each other on
the world's clock, and :class:`OrderLedger` keeps the orders in an
:class:`~plan_bridge.orders.book.OrderBook` and gives the figures of a planned order
mission (:meth:`OrderExecutive.figures <plan_bridge.orders.order_executive.OrderExecutive.figures>`).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import smach
from plan_bridge.execution.compile import TurnTakingConcurrence as ClockConcurrence
from plan_bridge.orders.book import OrderBook
from plan_bridge.pddl.task import Fact, format_fact
from plan_bridge.robosim.skills import skill_for
from plan_bridge.robosim.world import RobosimWorld

__all__ = [
    "ATTEMPTS",
    "RESERVE",
    "Act",
    "CheckBattery",
    "ClockSignal",
    "Delivery",
    "Drive",
    "OrderLedger",
    "SkillState",
    "TurnTakingConcurrence",
    "charger_spot",
    "deliver",
    "deliveries_of",
    "go_to",
    "locked_halls",
    "read_order_goal",
    "route",
    "route_length",
    "whereabouts",
]

#: Tries of one drive leg or action before a state gives up.
ATTEMPTS = 3
#: Battery (percent) a robot keeps in hand on top of the trip and the way to a charger.
RESERVE = 5.0
_FULL = 99.9


def route(world: RobosimWorld, start: str, goal: str, blocked: Iterable[str]) -> list[str] | None:
    """The shortest chain of places from ``start`` to ``goal`` on the map: places of
    one room are joined by drives, a hallway's two doorways by its crossing (not
    ``blocked`` ones); None when there is no way."""
    found = world.map.route(start, goal, set(blocked))
    return None if found is None else list(found.places)


def route_length(world: RobosimWorld, chain: list[str] | None) -> float:
    """Metres of a chain of places (infinite for no chain)."""
    if chain is None:
        return float("inf")
    edges = world.map.graph.edges
    return sum(float(edges[a, b]["weight"]) for a, b in itertools.pairwise(chain))


def charger_spot(world: RobosimWorld) -> str | None:
    """The place of the first charger of the world (None: the world has no charger)."""
    chargers = world.model.chargers()
    return chargers[0] if chargers else None


class SkillState(smach.State):
    """A state of ``robot`` that runs robosim skill machines; a preempt reaches the one
    running."""

    def __init__(self, world: RobosimWorld, robot: str, **keys: Any) -> None:
        super().__init__(**keys)
        self.world = world
        self.robot = robot
        self._running: smach.State | None = None

    def skill(self, action: str, *args: str) -> str:
        """Run the skill of ``(action robot *args)``; its outcome."""
        machine = skill_for(self.world, action, self.robot, *args)
        self._running = machine
        try:
            return str(machine.execute())
        finally:
            self._running = None

    def request_preempt(self) -> None:
        super().request_preempt()
        running = self._running
        if running is not None:
            running.request_preempt()

    def here(self) -> str:
        """The place the robot is at (the nearest of its room when between places)."""
        return self.world.spot_of(self.world.robot(self.robot))

    def gate_seen(self, gate: str) -> tuple[bool | None, bool | None]:
        """(open, locked) of a hallway or location as the robot sees it from where it
        is (None: it cannot see it from here)."""
        seen = dict(self.world.observe(self.world.robot(self.robot), [gate]))
        key = gate.lower()
        is_open, locked = seen.get(("isopen", key)), seen.get(("islocked", key))
        return (
            None if is_open is None else bool(is_open),
            None if locked is None else bool(locked),
        )


class CheckBattery(SkillState):
    """Enough battery for the trip to ``goal`` and from there to ``charger``: ``enough``;
    else ``low``; no way at all to the goal: ``no_way``. A robot with a full battery, or
    in a world without a charger, always has ``enough`` (charging cannot help)."""

    def __init__(self, world: RobosimWorld, robot: str, goal: str, charger: str | None) -> None:
        super().__init__(world, robot, outcomes=["enough", "low", "no_way"], input_keys=["blocked"])
        self.goal, self.charger = goal, charger

    def execute(self, ud: smach.UserData) -> str:
        blocked = set(ud.blocked)
        trip = route_length(self.world, route(self.world, self.here(), self.goal, blocked))
        if trip == float("inf"):
            return "no_way"
        if self.charger is None:
            return "enough"
        back = route_length(self.world, route(self.world, self.goal, self.charger, blocked))
        info = next(r for r in self.world.model.robots if r.name == self.robot)
        need = info.drain * (trip + (0.0 if back == float("inf") else back)) + RESERVE
        level = float(self.world.robot(self.robot).battery_level)
        return "enough" if level >= need or level >= _FULL else "low"


class Drive(SkillState):
    """Drive to ``goal`` leg by leg on the shortest way not known blocked, each leg tried
    three times. Before a crossing, a door seen closed is opened; a hallway seen locked,
    or one that would not open or stays impassable, is added to ``blocked`` and the
    state ends ``blocked`` (find another way)."""

    def __init__(self, world: RobosimWorld, robot: str, goal: str) -> None:
        super().__init__(
            world,
            robot,
            outcomes=["arrived", "blocked", "failed", "preempted"],
            io_keys=["blocked", "legs"],
        )
        self.goal = goal

    def execute(self, ud: smach.UserData) -> str:
        chain = route(self.world, self.here(), self.goal, ud.blocked)
        if chain is None:
            return "blocked"
        halls = {frozenset(hall.ends): hall.name for hall in self.world.model.halls.values()}
        for origin, target in itertools.pairwise(chain):
            hall = halls.get(frozenset((origin, target)))
            leg = ("cross", origin, target, hall) if hall else ("navigate", origin, target)
            for _ in range(ATTEMPTS):
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                if hall is not None and not self._door_passable(hall, origin):
                    return self._block(ud, hall)
                outcome = self.skill(*leg)
                ud.legs = [*ud.legs, " ".join(leg)]
                if outcome == "preempted":
                    return "preempted"
                if outcome == "succeeded" and self.here() == target:
                    break
                shut = self._locked_halls()
                if shut - set(ud.blocked):
                    ud.blocked = sorted({*ud.blocked, *shut})
                    return "blocked"
            else:
                return "failed"
        return "arrived"

    def _door_passable(self, hall: str, door: str) -> bool:
        """At the door ``door`` of ``hall``: open it if it is closed (three tries);
        False when it is locked or would not open."""
        is_open, locked = self.gate_seen(hall)
        if is_open is not False:
            return True
        if locked:
            return False
        for _ in range(ATTEMPTS):
            if self.skill("open", hall, door) == "succeeded":
                return True
            if self.gate_seen(hall)[1]:
                return False
        return False

    def _block(self, ud: smach.UserData, hall: str) -> str:
        ud.blocked = sorted({*ud.blocked, hall})
        return "blocked"

    def _locked_halls(self) -> set[str]:
        """The hallways the robot sees closed and locked from where it is."""
        seen = dict(self.world.observe(self.world.robot(self.robot), list(self.world.model.halls)))
        return {
            hall
            for hall in self.world.model.halls
            if seen.get(("isopen", hall.lower())) is False
            and seen.get(("islocked", hall.lower())) is not False
        }


class Act(SkillState):
    """One action of the robot, tried three times; opening what is open (or closing
    what is closed) is done at once."""

    def __init__(self, world: RobosimWorld, robot: str, action: str, *args: str) -> None:
        super().__init__(world, robot, outcomes=["done", "failed", "preempted"])
        self.action, self.args = action, args

    def execute(self, ud: smach.UserData) -> str:
        if self.action in ("open", "close"):
            is_open = bool(self.world.sim.get_entity_by_name(self.args[0]).is_open)
            if is_open == (self.action == "open"):
                return "done"
        for _ in range(ATTEMPTS):
            outcome = self.skill(self.action, *self.args)
            if outcome in ("succeeded", "preempted"):
                return "done" if outcome == "succeeded" else "preempted"
        return "failed"


def locked_halls(world: RobosimWorld) -> list[str]:
    """The hallways locked in the world as loaded: the ``blocked`` a mission starts with."""
    model = world.model
    return sorted(hall for hall in model.halls if model.gates[hall].is_locked)


#: The userdata keys of the machines here: hallways known blocked, legs driven.
KEYS = ["blocked", "legs"]


def _machine(*outcomes: str) -> smach.StateMachine:
    """A machine of :data:`KEYS` with ``outcomes`` and ``preempted``."""
    return smach.StateMachine(outcomes=[*outcomes, "preempted"], input_keys=KEYS, output_keys=KEYS)


def deliver(
    world: RobosimWorld,
    robot: str,
    item: str,
    target: str,
    charger: str | None = None,
    *,
    source: str | None = None,
    holding: bool = False,
) -> smach.StateMachine:
    """``GO_TO_OBJECT -> OPEN -> PICK -> GO_TO_TARGET -> PLACE``: carry ``item`` to spawn
    ``target``; outcomes ``done``, ``aborted``, ``preempted``. ``source``: the place the
    object lies at now (default: where the world file put it); ``holding``: the robot
    holds it already (the machine starts at ``GO_TO_TARGET``)."""
    model = world.model
    if source is None and not holding:
        source = model.item_place(item)
        if source is None:
            raise ValueError(f"{item} is held at the start: nothing to carry")
    target_location = model.places[target].fixture or ""
    sm = _machine("done", "aborted")
    with sm:
        if not holding and source is not None:
            location = model.places[source].fixture or ""
            smach.StateMachine.add(
                "GO_TO_OBJECT",
                go_to(world, robot, source, charger),
                {"arrived": "OPEN", "failed": "aborted"},
            )
            smach.StateMachine.add(
                "OPEN",
                Act(world, robot, "open", location, source),
                {"done": "PICK", "failed": "aborted"},
            )
            smach.StateMachine.add(
                "PICK",
                Act(world, robot, "pick", item, source, location),
                {"done": "GO_TO_TARGET", "failed": "aborted"},
            )
        smach.StateMachine.add(
            "GO_TO_TARGET",
            go_to(world, robot, target, charger),
            {"arrived": "PLACE", "failed": "aborted"},
        )
        smach.StateMachine.add(
            "PLACE",
            Act(world, robot, "place", item, target, target_location),
            {"failed": "aborted"},
        )
    return sm


def go_to(
    world: RobosimWorld, robot: str, goal: str, charger: str | None = None
) -> smach.StateMachine:
    """``CHECK_BATTERY -> DRIVE`` (another way when blocked), charging first when the
    battery is low: outcomes ``arrived``, ``failed``, ``preempted``."""
    sm = _machine("arrived", "failed")
    with sm:
        smach.StateMachine.add(
            "CHECK_BATTERY",
            CheckBattery(world, robot, goal, charger),
            {"enough": "DRIVE", "low": "TO_CHARGER" if charger else "DRIVE", "no_way": "failed"},
        )
        smach.StateMachine.add("DRIVE", Drive(world, robot, goal), {"blocked": "CHECK_BATTERY"})
        if charger is not None:
            location = world.model.places[charger].fixture or ""
            smach.StateMachine.add(
                "TO_CHARGER",
                Drive(world, robot, charger),
                {"arrived": "CHARGE", "blocked": "failed"},
            )
            smach.StateMachine.add(
                "CHARGE", Act(world, robot, "charge", charger, location), {"done": "CHECK_BATTERY"}
            )
    return sm


class TurnTakingConcurrence(ClockConcurrence):
    """A Concurrence whose children (one machine per robot, say) take turns on the
    world's simulated clock, as the steps of a planned mission do
    (:class:`plan_bridge.execution.compile.TurnTakingConcurrence` on ``world.clock``).
    The world's time is then the latest child's timeline, not the sum of theirs, what
    one robot changes reaches the other in one order, and a seeded run repeats exactly.
    The other arguments are :class:`smach.Concurrence`'s.
    """

    def __init__(
        self,
        world: RobosimWorld,
        outcomes: Iterable[str],
        default_outcome: str | None = None,
        **options: Any,
    ) -> None:
        super().__init__(world.clock, list(outcomes), default_outcome, **options)
        self.world = world


# -- orders dispatched by hand -------------------------------------------------------------
@dataclass(frozen=True)
class Delivery:
    """An object to bring to a spawn: a goal atom ``(At OBJECT SPAWN)`` (``target`` is
    the spawn's place)."""

    item: str
    target: str


def read_order_goal(world: RobosimWorld, folder: Path, text: str) -> list[Fact]:
    """An order's goal read as the planned mission reads it: the name of a goal of the
    folder's goals.yaml, or atoms in pyrobosim's vocabulary. Raises
    :class:`~plan_bridge.errors.PlanBridgeError` saying what is wrong."""
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.maps.goals import parse_goal
    from plan_bridge.pddl.constructs import did_you_mean
    from plan_bridge.robosim.target_files import read_goals

    word = text.strip()
    if re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", word):
        goals = read_goals(folder)
        if word not in goals:
            raise PlanBridgeError(
                f"{word}: not a goal atom such as (At apple0 table0_tabletop), nor the name of "
                f"a goal{did_you_mean(word, goals)}; goals of {folder}/goals.yaml: "
                + ", ".join(goals)
            )
        word = goals[word]
    return parse_goal(word, world.model)


def deliveries_of(world: RobosimWorld, atoms: Sequence[Fact]) -> list[Delivery]:
    """The deliveries of a goal of ``(At OBJECT SPAWN)`` atoms (``(Has LOCATION
    OBJECT)`` of a location with one spawn too). Raises ``ValueError`` naming an atom
    that is not a delivery."""
    model = world.model
    found: list[Delivery] = []
    for atom in atoms:
        name, *args = atom
        item = target = ""
        if name == "at" and len(args) == 2 and world.name(args[0]) in model.items:
            item, target = world.name(args[0]), world.name(args[1])
        elif name == "has" and len(args) == 2 and world.name(args[1]) in model.items:
            places = model.spawn_places(world.name(args[0]))
            item, target = world.name(args[1]), places[0] if len(places) == 1 else ""
        if not item or target not in model.places or not model.places[target].is_spawn:
            raise ValueError(
                f"{format_fact(atom)}: the script delivers objects to spawns: (At OBJECT SPAWN)"
            )
        found.append(Delivery(item, target))
    return found


def whereabouts(world: RobosimWorld, item: str) -> tuple[str | None, str | None]:
    """Where ``item`` is now: (the place of the spawn it lies on, the robot holding it);
    (None, None) when it is nowhere (an event took it away)."""
    obj = world.sim.get_object_by_name(item)
    if obj is None:
        return None, None
    for robot in world.sim.robots:
        if robot.manipulated_object is obj:
            return None, str(robot.name)
    spawn = obj.parent
    return (None if spawn is None else world.model.spawn_place(spawn.name)), None


class ClockSignal:
    """News between the participants of the world's clock (a dispatcher and the robots'
    machines in a :class:`TurnTakingConcurrence`): :meth:`wait` gives up the turn until
    :meth:`notify` or, when given, a time of the world's clock, whichever comes first.
    Only one participant runs at a time, so whatever a waiter looked at before waiting
    is still so when it waits: no news is missed."""

    def __init__(self, world: RobosimWorld) -> None:
        self.clock = world.clock
        self.condition = world.clock.condition()

    def wait(self, until: float | None = None) -> None:
        if not self.clock.taking_part():  # a thread of its own: it moves the clock itself
            if until is not None:
                self.clock.sleep_until(until)
            return
        with self.condition:
            self.condition.wait_until(until)

    def notify(self) -> None:
        with self.condition:
            self.condition.notify_all()


class OrderLedger:
    """The orders of a mission dispatched by hand, in an
    :class:`~plan_bridge.orders.book.OrderBook` (``orders``) on the world's clock
    (seconds since the ledger was made), with each robot's seconds at work
    (``busy_s``): :meth:`figures` are those of a planned order mission."""

    def __init__(self, world: RobosimWorld, orders: OrderBook, robots: Iterable[str]) -> None:
        self.world = world
        self.orders = orders
        self.robots = tuple(robots)
        self.busy_s: dict[str, float] = {}
        self.t0 = world.now()
        self.elapsed_s = 0.0
        """The mission's clock at its end (set by :meth:`close`)."""

    def now(self) -> float:
        """The mission's clock: seconds of the world's clock since the ledger was made."""
        return self.world.now() - self.t0

    def worked(self, robot: str, seconds: float) -> None:
        """``robot`` spent ``seconds`` on an order."""
        self.busy_s[robot] = self.busy_s.get(robot, 0.0) + max(0.0, seconds)

    def close(self) -> None:
        """The mission ended now."""
        self.elapsed_s = self.now()

    def figures(self) -> dict[str, Any]:
        """The book's summary (counts, latency p50/p95, orders done per hour) and each
        robot's share of the mission's time at work, as a planned order mission's."""
        data = self.orders.summary(self.elapsed_s)
        if self.elapsed_s > 0:
            data["busy_share"] = {
                robot: round(self.busy_s.get(robot, 0.0) / self.elapsed_s, 4)
                for robot in sorted(self.robots)
            }
        return data
