"""A planned mission in code: PDDL goal -> plan -> hand-written SMACH skills -> replanning.

Run: ``python examples/planned_mission.py``

A robot must bring a cup to the office. The domain is given as PDDL text, each action
has a small SMACH skill acting on a toy world, and the first attempt to pick the cup
finds it gone: the skill reports where it saw it, the executive repairs or replans,
and the mission still ends with the cup in the office.
"""

from __future__ import annotations

import sys

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.pddl.task import load_task_from_text
from plan_bridge.skills.registry import SkillRegistry

DOMAIN = """
(define (domain deliver)
  (:requirements :strips :typing)
  (:types room item)
  (:predicates (robot-at ?r - room) (at ?i - item ?r - room) (holding ?i - item)
               (hand-free) (door ?a - room ?b - room))
  (:action go :parameters (?from ?to - room)
    :precondition (and (robot-at ?from) (door ?from ?to))
    :effect (and (robot-at ?to) (not (robot-at ?from))))
  (:action pick :parameters (?i - item ?r - room)
    :precondition (and (robot-at ?r) (at ?i ?r) (hand-free))
    :effect (and (holding ?i) (not (at ?i ?r)) (not (hand-free))))
  (:action place :parameters (?i - item ?r - room)
    :precondition (and (robot-at ?r) (holding ?i))
    :effect (and (at ?i ?r) (hand-free) (not (holding ?i)))))
"""

PROBLEM = """
(define (problem cup-to-office) (:domain deliver)
  (:objects hall kitchen office - room cup - item)
  (:init (robot-at hall) (hand-free) (at cup kitchen)
         (door hall kitchen) (door kitchen hall) (door hall office) (door office hall))
  (:goal (at cup office)))
"""


class World:
    """The real world: somebody already carried the cup to the hall."""

    def __init__(self) -> None:
        self.robot = "hall"
        self.cup = "hall"
        self.holding = False


def build_skills(world: World) -> SkillRegistry:
    skills = SkillRegistry()
    outcomes = ["succeeded", "aborted", "preempted"]

    @skills.register("go")
    def go(src: str, dst: str) -> smach.State:
        def drive(ud: smach.UserData) -> str:
            world.robot = dst
            return "succeeded"

        return smach.CBState(drive, outcomes=outcomes)

    @skills.register("pick")
    def pick(item: str, room: str) -> smach.State:
        """DETECT -> GRASP: detection reports where the item really is."""
        sm = smach.StateMachine(outcomes=outcomes, output_keys=["observations"])

        def detect(ud: smach.UserData) -> str:
            if world.cup != room:
                ud.observations = {f"(at {item} {room})": False, f"(at {item} {world.cup})": True}
                return "aborted"
            return "succeeded"

        def grasp(ud: smach.UserData) -> str:
            world.holding, world.cup = True, "gripper"
            return "succeeded"

        with sm:
            smach.StateMachine.add(
                "DETECT",
                smach.CBState(
                    detect, outcomes=["succeeded", "aborted"], output_keys=["observations"]
                ),
                transitions={"succeeded": "GRASP"},
            )
            smach.StateMachine.add("GRASP", smach.CBState(grasp, outcomes=["succeeded"]))
        return sm

    @skills.register("place")
    def place(item: str, room: str) -> smach.State:
        def put(ud: smach.UserData) -> str:
            world.holding, world.cup = False, world.robot
            return "succeeded"

        return smach.CBState(put, outcomes=outcomes)

    return skills


def main() -> int:
    world = World()
    task = load_task_from_text(DOMAIN, PROBLEM)
    executive = Executive(task, build_skills(world))
    mission = smach.StateMachine(outcomes=["delivered", "failed"])
    with mission:
        smach.StateMachine.add(
            "DELIVER",
            executive,
            transitions={"succeeded": "delivered", "aborted": "failed", "preempted": "failed"},
        )
    outcome = mission.execute()
    report = executive.report
    for decision in report.decisions:
        print(f"decision: {decision['decision']}: {decision['reason']}")
    print(f"executed: {' '.join(report.executed)}")
    print(f"outcome: {outcome}; cup in {world.cup}; {report.planner_calls} planner calls")
    return 0 if outcome == "delivered" and world.cup == "office" else 1


if __name__ == "__main__":
    sys.exit(main())
