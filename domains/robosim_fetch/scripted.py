"""robosim_fetch written by hand: one SMACH machine with explicit recovery, no planner.

The baseline of the scripted-vs-planned study on this pyrobosim world. It drives the
same robosim skills as the planned missions (``plan_bridge.robosim.skills.skill_for``:
pyrobosim's path planner and executor, pick, place, open, charge) in the same
:class:`~plan_bridge.robosim.world.RobosimWorld`, with the recoveries its author
anticipated:

* a drive or an action that fails: try it again from where the robot is (three tries);
* a hallway found closed (a cross refused, or the robot sees it shut after a failed
  drive): never use it again, take the shortest way through the other hallways;
* a battery too low for the next trip and the way from its end to the charger: go and
  charge first.

It fetches an object to a spawn, goals ``(At OBJECT SPAWN)`` (with ``(HandEmpty
ROBOT)`` if wanted): ``fetch_soda`` and ``apple_to_table`` of goals.yaml. Anything
unanticipated (every way closed, three failures in a row) ends it ``aborted``::

    GO_TO_OBJECT -> OPEN -> PICK -> GO_TO_TARGET -> PLACE -> succeeded
    GO_TO_X = CHECK_BATTERY --enough--> DRIVE --blocked--> CHECK_BATTERY (another way)
                            --low--> TO_CHARGER -> CHARGE -> CHECK_BATTERY
"""

from __future__ import annotations

import heapq
import itertools
from pathlib import Path
from typing import Any

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import variant_events
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.robosim.skills import skill_for
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["route", "scripted"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]
#: Tries of one drive leg or action before the machine gives up.
ATTEMPTS = 3
#: Battery (percent) the robot keeps in hand on top of the trip and the way to a charger.
RESERVE = 5.0
FULL = 99.9


def route(world: RobosimWorld, start: str, goal: str, closed: set[str]) -> list[str] | None:
    """The shortest chain of spots from ``start`` to ``goal`` on the map: spots of one
    room are joined by drives, a hallway's two ends by its crossing (not ``closed`` ones)."""
    model = world.model
    ends = {frozenset(pair): hall for hall, pair in model.hall_ends.items() if hall not in closed}
    best = {start: 0.0}
    before: dict[str, str] = {}
    queue = [(0.0, start)]
    while queue:
        cost, spot = heapq.heappop(queue)
        if spot == goal:
            chain = [goal]
            while chain[-1] != start:
                chain.append(before[chain[-1]])
            return chain[::-1]
        if cost > best[spot]:
            continue
        room = model.spots[spot].room
        for other in model.spots.values():
            joined = other.room == room or frozenset((spot, other.name)) in ends
            if other.name == spot or not joined:
                continue
            step = cost + model.distance(spot, other.name)
            if step < best.get(other.name, float("inf")):
                best[other.name], before[other.name] = step, spot
                heapq.heappush(queue, (step, other.name))
    return None


def _length(world: RobosimWorld, chain: list[str] | None) -> float:
    if chain is None:
        return float("inf")
    return sum(world.model.distance(a, b) for a, b in itertools.pairwise(chain))


class _SkillState(smach.State):
    """Runs robosim skill machines; a preempt reaches the one running."""

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
        return self.world.spot_of(self.world.robot(self.robot))


class CheckBattery(_SkillState):
    """Enough battery for the trip to ``goal`` and from there to a charger? No way at
    all (every hallway to it closed): ``no_way``."""

    def __init__(self, world: RobosimWorld, robot: str, goal: str, charger: str) -> None:
        super().__init__(world, robot, outcomes=["enough", "low", "no_way"], input_keys=["closed"])
        self.goal, self.charger = goal, charger

    def execute(self, ud: smach.UserData) -> str:
        closed = set(ud.closed)
        trip = _length(self.world, route(self.world, self.here(), self.goal, closed))
        if trip == float("inf"):
            return "no_way"
        back = _length(self.world, route(self.world, self.goal, self.charger, closed))
        info = next(r for r in self.world.model.robots if r.name == self.robot)
        need = info.drain * (trip + (0.0 if back == float("inf") else back)) + RESERVE
        level = float(self.world.robot(self.robot).battery_level)
        # A full battery that is not enough: go anyway (charging cannot help).
        return "enough" if level >= need or level >= FULL else "low"


class Drive(_SkillState):
    """Drive to ``goal`` leg by leg on the shortest open way, each leg tried three times.
    A hallway the robot finds closed is added to ``closed`` (``blocked``: find another way)."""

    def __init__(self, world: RobosimWorld, robot: str, goal: str) -> None:
        super().__init__(
            world,
            robot,
            outcomes=["arrived", "blocked", "failed", "preempted"],
            io_keys=["closed", "legs"],
        )
        self.goal = goal

    def execute(self, ud: smach.UserData) -> str:
        chain = route(self.world, self.here(), self.goal, set(ud.closed))
        if chain is None:
            return "blocked"
        halls = {frozenset(pair): hall for hall, pair in self.world.model.hall_ends.items()}
        for origin, target in itertools.pairwise(chain):
            hall = halls.get(frozenset((origin, target)))
            leg = ("cross", origin, target, hall) if hall else ("navigate", origin, target)
            for _ in range(ATTEMPTS):
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                outcome = self.skill(*leg)
                ud.legs = [*ud.legs, " ".join(leg)]
                if outcome == "preempted":
                    return "preempted"
                if outcome == "succeeded" and self.here() == target:
                    break
                shut = self._closed_halls()
                if shut - set(ud.closed):
                    ud.closed = sorted({*ud.closed, *shut})
                    return "blocked"
            else:
                return "failed"
        return "arrived"

    def _closed_halls(self) -> set[str]:
        """The hallways the robot sees closed from where it is."""
        robot = self.world.robot(self.robot)
        seen = dict(self.world.observe(robot, list(self.world.model.hall_ends)))
        return {
            hall
            for hall in self.world.model.hall_ends
            if seen.get(("isopen", hall.lower())) is False
        }


class Act(_SkillState):
    """One action, tried three times; ``open`` only when the location is closed."""

    def __init__(self, world: RobosimWorld, robot: str, action: str, *args: str) -> None:
        super().__init__(world, robot, outcomes=["done", "failed", "preempted"])
        self.action, self.args = action, args

    def execute(self, ud: smach.UserData) -> str:
        if self.action == "open" and self.world.sim.get_entity_by_name(self.args[0]).is_open:
            return "done"
        for _ in range(ATTEMPTS):
            outcome = self.skill(self.action, *self.args)
            if outcome in ("succeeded", "preempted"):
                return "done" if outcome == "succeeded" else "preempted"
        return "failed"


def go_to(world: RobosimWorld, robot: str, goal: str, charger: str) -> smach.StateMachine:
    """CHECK_BATTERY -> DRIVE (another way when blocked), charging first when low."""
    sm = smach.StateMachine(
        outcomes=["arrived", "failed", "preempted"], input_keys=["closed", "legs"],
        output_keys=["closed", "legs"],
    )  # fmt: skip
    charger_location = world.model.spots[charger].gate or ""
    with sm:
        smach.StateMachine.add(
            "CHECK_BATTERY",
            CheckBattery(world, robot, goal, charger),
            {"enough": "DRIVE", "low": "TO_CHARGER", "no_way": "failed"},
        )
        smach.StateMachine.add("DRIVE", Drive(world, robot, goal), {"blocked": "CHECK_BATTERY"})
        smach.StateMachine.add(
            "TO_CHARGER", Drive(world, robot, charger), {"arrived": "CHARGE", "blocked": "failed"}
        )
        smach.StateMachine.add(
            "CHARGE",
            Act(world, robot, "charge", charger, charger_location),
            {"done": "CHECK_BATTERY"},
        )
    return sm


def _fetch_goal(task: PlanningTask, world: RobosimWorld) -> tuple[str, str, str]:
    """(robot, object, spawn) of a goal (At OBJECT SPAWN) [(HandEmpty ROBOT)]."""
    model = world.model
    robot = model.robots[0].name
    wanted = [
        (world.name(f[1]), world.name(f[2]))
        for f in task.goal_facts
        if f[0] == "at" and world.name(f[1]) in model.items
    ]
    others = [
        f
        for f in task.goal_facts
        if f[0] != "handempty" and not (f[0] == "at" and world.name(f[1]) in model.items)
    ]
    spawn = wanted[0][1] if len(wanted) == 1 else ""
    if others or spawn not in model.spots or model.spots[spawn].kind != "spawn":
        raise ValueError(
            "the scripted baseline of robosim_fetch fetches one object to a spawn: a goal "
            f"(At OBJECT SPAWN), optionally with (HandEmpty {robot}); not {task.goal_facts}"
        )
    return robot, *wanted[0]


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = RobosimWorld(
        FOLDER / "world.yaml",
        task.goal_facts,
        seed=seed,
        fail_rate=fail_rate,
        events=variant_events(FOLDER, variant),
    )
    model = world.model
    robot, item, target = _fetch_goal(task, world)
    source = model.items[item]
    if source is None:
        raise ValueError(f"{item} is held at the start: nothing to fetch")
    charger = next(g.spawns[0] for g in model.gates.values() if g.is_charger and g.spawns)
    mission = smach.StateMachine(outcomes=OUTCOMES)
    mission.userdata.closed = sorted(h for h in model.hall_ends if not model.gates[h].is_open)
    mission.userdata.legs = []
    location, target_location = model.spots[source].gate or "", model.spots[target].gate or ""
    with mission:
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
            {"done": "succeeded", "failed": "aborted"},
        )
    return ScriptedMission(mission, world)
