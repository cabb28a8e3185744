"""recharge written by hand: one SMACH machine with explicit recovery, no planner.

The author read the deliveries off the problem, drives with the navigation stack's
global planner (routes are computed on the floor plan when a leg starts), and
anticipated the low battery: every drive runs next to the battery monitor, and when
it fires the machine docks, plugs in (three attempts), charges, unplugs and drives
the interrupted leg again. Per delivery::

    GO_TO_ITEM_i --battery_low--> RECHARGE_FOR_ITEM_i --> GO_TO_ITEM_i
        --arrived--> PICK_i --> GO_TO_TARGET_i --battery_low--> RECHARGE_FOR_TARGET_i
        --> GO_TO_TARGET_i --arrived--> PLACE_i --> (next delivery | succeeded)
    GO_TO_X = PLAN_ROUTE -> DRIVE_WITH_MONITOR
    RECHARGE = DOCK (PLAN_ROUTE -> DOCK) -> PLUG_IN (Retry x3) -> CHARGE -> UNPLUG

Unanticipated trouble ends the mission ``aborted``: a plug that misses the socket
three times, a grasp that slips twice, a battery emptied on the way to the dock.
"""

from __future__ import annotations

import smach
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import PlanningTask

from .skills import (
    PlanRoute,
    charge_state,
    dock_behaviour,
    drive_with_monitor,
    pick_behaviour,
    place_state,
    plug_in_behaviour,
    unplug_state,
)
from .world import RechargeWorld

__all__ = ["go_to_behaviour", "recharge_behaviour", "scripted"]


def go_to_behaviour(world: RechargeWorld) -> smach.StateMachine:
    """PLAN_ROUTE -> DRIVE_WITH_MONITOR: arrived / battery_low / failed."""
    sm = smach.StateMachine(
        outcomes=["arrived", "battery_low", "failed", "preempted"],
        input_keys=["robot", "destination"],
    )
    with sm:
        smach.StateMachine.add(
            "PLAN_ROUTE",
            PlanRoute(world),
            {"planned": "DRIVE_WITH_MONITOR", "unreachable": "failed"},
        )
        smach.StateMachine.add("DRIVE_WITH_MONITOR", drive_with_monitor(world))
    return sm


def recharge_behaviour(world: RechargeWorld) -> smach.StateMachine:
    """DOCK -> PLUG_IN -> CHARGE -> UNPLUG: charged / failed."""
    sm = smach.StateMachine(outcomes=["charged", "failed", "preempted"], input_keys=["robot"])
    sm.userdata.dock = world.chargers[0]
    with sm:
        smach.StateMachine.add(
            "DOCK", dock_behaviour(world), {"docked": "PLUG_IN"}, remapping={"destination": "dock"}
        )
        smach.StateMachine.add("PLUG_IN", plug_in_behaviour(world), {"plugged": "CHARGE"})
        smach.StateMachine.add("CHARGE", charge_state(world), {"charged": "UNPLUG"})
        smach.StateMachine.add("UNPLUG", unplug_state(world), {"unplugged": "charged"})
    return sm


def scripted(task: PlanningTask, *, seed: int, fail_rate: float) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = RechargeWorld(task, seed=seed, fail_rate=fail_rate)
    believed_at = {f[1]: f[2] for f in task.initial_facts if f[0] == "item-at"}
    deliveries = [(g[1], believed_at[g[1]], g[2]) for g in task.goal_facts if g[0] == "item-at"]
    mission = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    mission.userdata.robot = world.robot

    def add_go_to(leg: str, destination: str, arrived: str) -> None:
        """GO_TO_<leg>; when the battery runs low on the way, RECHARGE_FOR_<leg>, then again."""
        smach.StateMachine.add(
            f"GO_TO_{leg}",
            go_to_behaviour(world),
            {"arrived": arrived, "battery_low": f"RECHARGE_FOR_{leg}", "failed": "aborted"},
            remapping={"destination": destination},
        )
        smach.StateMachine.add(
            f"RECHARGE_FOR_{leg}",
            recharge_behaviour(world),
            {"charged": f"GO_TO_{leg}", "failed": "aborted"},
        )

    with mission:
        for n, (item, source, target) in enumerate(deliveries, start=1):
            done = "succeeded" if n == len(deliveries) else f"GO_TO_ITEM_{n + 1}"
            mission.userdata[f"item_{n}"] = item
            mission.userdata[f"source_{n}"] = source
            mission.userdata[f"target_{n}"] = target
            add_go_to(f"ITEM_{n}", f"source_{n}", f"PICK_{n}")
            smach.StateMachine.add(
                f"PICK_{n}",
                pick_behaviour(world),
                {"picked": f"GO_TO_TARGET_{n}", "failed": "aborted"},
                remapping={"item": f"item_{n}", "room": f"source_{n}"},
            )
            add_go_to(f"TARGET_{n}", f"target_{n}", f"PLACE_{n}")
            smach.StateMachine.add(
                f"PLACE_{n}",
                place_state(world),
                {"placed": done, "failed": "aborted"},
                remapping={"item": f"item_{n}"},
            )
    return ScriptedMission(mission, world)
