"""robosim_fetch written by hand: one SMACH machine with explicit recovery, no planner.

The baseline of the scripted-vs-planned study on this pyrobosim world. It drives the
same robosim skills as the planned missions (``plan_bridge.robosim.skills.skill_for``:
pyrobosim's path planner and executor, pick, place, open, charge) in the same
:class:`~plan_bridge.robosim.world.RobosimWorld`, with the recoveries its author
anticipated:

* a drive or an action that fails: try it again from where the robot is (three tries);
* a door found closed on the way: open it; a hallway found locked (or one that will
  not open): never use it again, take the shortest way through the other hallways;
* a battery too low for the next trip and the way from its end to the charger: go and
  charge first.

It fetches an object to a spawn, goals ``(At OBJECT SPAWN)`` (with ``(HandEmpty
ROBOT)`` if wanted): ``fetch_soda`` and ``apple_to_table`` of goals.yaml. Anything
unanticipated (every way closed, three failures in a row) ends it ``aborted``::

    FETCH (GO_TO_OBJECT -> OPEN -> PICK -> GO_TO_TARGET -> PLACE) -> succeeded
    GO_TO_X = CHECK_BATTERY --enough--> DRIVE --blocked--> CHECK_BATTERY (another way)
                            --low--> TO_CHARGER -> CHARGE -> CHECK_BATTERY

The states are :mod:`plan_bridge.robosim.scripting`'s.
"""

from __future__ import annotations

from pathlib import Path

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.missions.world_target import scripted_world
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.robosim.scripting import charger_spot, deliver, locked_halls
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["scripted"]

FOLDER = Path(__file__).resolve().parent
OUTCOMES = ["succeeded", "aborted", "preempted"]


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
    if others or spawn not in model.places or not model.places[spawn].is_spawn:
        raise ValueError(
            "the scripted baseline of robosim_fetch fetches one object to a spawn: a goal "
            f"(At OBJECT SPAWN), optionally with (HandEmpty {robot}); not {task.goal_facts}"
        )
    return robot, *wanted[0]


def scripted(
    task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = scripted_world(FOLDER, task, seed=seed, fail_rate=fail_rate, variant=variant)
    robot, item, target = _fetch_goal(task, world)
    mission = smach.StateMachine(outcomes=OUTCOMES)
    mission.userdata.blocked = locked_halls(world)
    mission.userdata.legs = []
    with mission:
        smach.StateMachine.add(
            "FETCH",
            deliver(world, robot, item, target, charger_spot(world)),
            {"done": "succeeded"},
        )
    return ScriptedMission(mission, world)
