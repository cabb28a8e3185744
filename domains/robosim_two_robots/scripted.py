"""robosim_two_robots written by hand: one SMACH machine per robot, both at once.

The baseline of the scripted-vs-planned study on this world. Its author splits the
work before the robots start and writes no planner:

* every delivery of the goal, ``(At OBJECT SPAWN)``, goes to one robot: of all the
  ways to share the deliveries out, the one whose busiest robot drives the least
  (shortest ways on the map; a robot does its deliveries in the goal's order);
* a delivery into a closed location (the lab's locker) needs it opened with an empty
  hand: the other robot goes there first and opens it, and the carrier waits at the
  locker until it is open (``WAIT_OPEN``, at most :data:`PATIENCE_S`);
* on the way, the recoveries of :mod:`plan_bridge.robosim.scripting`: a drive or
  an action tried three times, a closed door opened, another way when a hallway is
  found locked (the robots share what they found: the userdata key ``blocked``),
  charging first when the battery is low.

The robots' machines run in a :class:`~plan_bridge.robosim.scripting.TurnTakingConcurrence`:
at once, taking turns on the world's simulated clock (the mission's time is the
slower robot's, and a seeded run repeats exactly). It succeeds when both machines do;
a robot that gives up leaves the other to finish its part (``aborted``)::

    ROBOT = [GO_TO_<LOCATION> -> OPEN_<LOCATION>]      (a location to open for the other)
            GO_TO_<ITEM> -> OPEN_FOR_<ITEM> -> PICK_<ITEM> -> CARRY_<ITEM>
            -> WAIT_OPEN_<ITEM> -> PLACE_<ITEM> ...     (each of its deliveries)
    ADA, BOB: one ROBOT machine each, in the TurnTakingConcurrence
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import scripted_world
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.robosim.scripting import (
    Act,
    TurnTakingConcurrence,
    charger_spot,
    go_to,
    locked_halls,
    route,
    route_length,
)
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["PATIENCE_S", "Delivery", "Jobs", "WaitOpen", "scripted", "share_out"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]
#: Simulated seconds a carrier waits at a closed location for the other robot to open it.
PATIENCE_S = 120.0


@dataclass(frozen=True)
class Delivery:
    """An object to bring from the spawn it is on to a spawn."""

    item: str
    source: str
    target: str


@dataclass
class Jobs:
    """What one robot does, in order: locations to open, then deliveries."""

    opens: list[str] = field(default_factory=list)
    """Spawns whose location it opens (with an empty hand), first of all."""
    deliveries: list[Delivery] = field(default_factory=list)


def _deliveries(task: PlanningTask, world: RobosimWorld) -> list[Delivery]:
    """The deliveries of a goal of (At OBJECT SPAWN) atoms (and HandEmpty ones)."""
    model = world.model
    wanted: list[Delivery] = []
    others = []
    for fact in task.goal_facts:
        if fact[0] == "at" and world.name(fact[1]) in model.items:
            item, target = world.name(fact[1]), world.name(fact[2])
            source = model.item_place(item)
            if target not in model.places or not model.places[target].is_spawn:
                others.append(fact)
            elif source is None:
                raise ValueError(f"{item} is held at the start: the baseline fetches from spawns")
            elif source != target:
                wanted.append(Delivery(item, source, target))
        elif fact[0] != "handempty":
            others.append(fact)
    if others or not wanted:
        raise ValueError(
            "the scripted baseline of robosim_two_robots brings objects to spawns: a goal of "
            f"(At OBJECT SPAWN) atoms, optionally with (HandEmpty ROBOT); not {task.goal_facts}"
        )
    return wanted


def _closed(world: RobosimWorld, spawn: str) -> bool:
    gate = world.model.places[spawn].fixture
    return gate is not None and not world.model.gates[gate].is_open


def _metres(world: RobosimWorld, start: str, stops: list[str]) -> float:
    """Metres of the shortest ways from ``start`` through ``stops`` in order."""
    blocked = [h for h in world.model.halls if world.model.gates[h].is_locked]
    here, total = start, 0.0
    for stop in stops:
        total += route_length(world, route(world, here, stop, blocked))
        here = stop
    return total


def share_out(world: RobosimWorld, deliveries: list[Delivery]) -> dict[str, Jobs]:
    """Each robot's jobs: the sharing of the deliveries whose busiest robot drives the
    least (then: the least in all; then: the first robots first), and the opening of a
    closed target location by a robot that does not carry into it."""
    robots = [r.name for r in world.model.robots]
    starts = {r: world.spot_of(world.robot(r)) for r in robots}
    best: tuple[float, float] | None = None
    chosen: dict[str, Jobs] = {}
    for owners in itertools.product(robots, repeat=len(deliveries)):
        jobs = {r: Jobs() for r in robots}
        for owner, delivery in zip(owners, deliveries, strict=True):
            jobs[owner].deliveries.append(delivery)
        for owner, delivery in zip(owners, deliveries, strict=True):
            if _closed(world, delivery.target):
                helpers = [r for r in robots if r != owner and not jobs[r].deliveries]
                helpers = helpers or [r for r in robots if r != owner]
                if helpers and delivery.target not in jobs[helpers[0]].opens:
                    jobs[helpers[0]].opens.append(delivery.target)
        lengths = [
            _metres(
                world,
                starts[r],
                [*jobs[r].opens, *(s for d in jobs[r].deliveries for s in (d.source, d.target))],
            )
            for r in robots
        ]
        score = (max(lengths), sum(lengths))
        if best is None or score < best:
            best, chosen = score, jobs
    return chosen


class WaitOpen(smach.State):
    """Wait on the world's clock until the location of ``spawn`` is open (another
    robot opens it): ``open``; still closed after ``patience`` simulated seconds:
    ``closed``."""

    def __init__(self, world: RobosimWorld, spawn: str, patience: float = PATIENCE_S) -> None:
        super().__init__(outcomes=["open", "closed", "preempted"])
        self.world, self.patience = world, patience
        self.gate = world.model.places[spawn].fixture or ""

    def execute(self, ud: smach.UserData) -> str:
        if not self.gate:
            return "open"
        entity = self.world.sim.get_entity_by_name(self.gate)
        deadline = self.world.now() + self.patience
        while not entity.is_open:
            if self.world.now() >= deadline:
                return "closed"
            if not self.world.clock.sleep(1.0, self.preempt_requested):
                self.service_preempt()
                return "preempted"
        return "open"


def _robot_machine(
    world: RobosimWorld, robot: str, jobs: Jobs, charger: str | None
) -> smach.StateMachine:
    """One robot's jobs in a row (``IDLE`` when it has none): ``succeeded``, ``aborted``
    (a job it gave up), ``preempted``."""
    keys = ["blocked", "legs"]
    sm = smach.StateMachine(outcomes=OUTCOMES, input_keys=keys, output_keys=keys)
    model = world.model
    stages: list[tuple[str, smach.State, dict[str, str]]] = []
    for spawn in jobs.opens:
        gate = model.places[spawn].fixture or ""
        name = gate.upper()
        stages.append((f"GO_TO_{name}", go_to(world, robot, spawn, charger), {}))
        stages.append((f"OPEN_{name}", Act(world, robot, "open", gate, spawn), {}))
    for delivery in jobs.deliveries:
        item, source, target = delivery.item, delivery.source, delivery.target
        name = item.upper()
        location = model.places[source].fixture or ""
        target_location = model.places[target].fixture or ""
        stages += [
            (f"GO_TO_{name}", go_to(world, robot, source, charger), {}),
            (f"OPEN_FOR_{name}", Act(world, robot, "open", location, source), {}),
            (f"PICK_{name}", Act(world, robot, "pick", item, source, location), {}),
            (f"CARRY_{name}", go_to(world, robot, target, charger), {}),
            (f"WAIT_OPEN_{name}", WaitOpen(world, target), {"closed": "aborted"}),
            (f"PLACE_{name}", Act(world, robot, "place", item, target, target_location), {}),
        ]
    with sm:
        if not stages:
            smach.StateMachine.add(
                "IDLE", smach.CBState(lambda ud: "succeeded", outcomes=["succeeded"])
            )
        for n, (label, state, extra) in enumerate(stages):
            following = stages[n + 1][0] if n + 1 < len(stages) else "succeeded"
            done = {"arrived": following, "done": following, "open": following}
            failed = {"failed": "aborted", "preempted": "preempted"}
            outcomes = state.get_registered_outcomes()
            transitions = {k: v for k, v in {**done, **failed}.items() if k in outcomes}
            smach.StateMachine.add(label, state, {**transitions, **extra})
    return sm


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """Both robots' machines at once, acting on a fresh world."""
    world = scripted_world(FOLDER, task, seed=seed, fail_rate=fail_rate, variant=variant)
    jobs = share_out(world, _deliveries(task, world))
    charger = charger_spot(world)
    robots = [r.name for r in world.model.robots]
    legs = [f"{robot}_legs" for robot in robots]
    mission = TurnTakingConcurrence(
        world,
        outcomes=OUTCOMES,
        default_outcome="aborted",
        outcome_map={"succeeded": {robot.upper(): "succeeded" for robot in robots}},
        input_keys=["blocked", *legs],
        output_keys=["blocked", *legs],
    )
    mission.userdata.blocked = locked_halls(world)
    for robot, key in zip(robots, legs, strict=True):
        mission.userdata[key] = []
        machine = _robot_machine(world, robot, jobs[robot], charger)
        mission.add(robot.upper(), machine, remapping={"legs": key})
    return ScriptedMission(mission, world, extra={"jobs": jobs})
