"""A knowledge base: the problem built change by change, and a mission that follows it.

Run: ``python examples/knowledge_base.py``

The problem is not a file: it is built in a KnowledgeBase, checked against the domain
at every change (a misspelt predicate is refused with "did you mean"). The mission
follows the knowledge base: when the robot enters the kitchen its camera "sees" a
mug, perception adds the mug to the knowledge base and an operator asks for it in
the office; the executive stops its plan, replans for the new goal and delivers both.
The same changes can come over ROS 2 (``KnowledgeServices``, docs/planning.md).
"""

from __future__ import annotations

import sys

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.pddl.knowledge import KnowledgeBase, KnowledgeError
from plan_bridge.skills.registry import SkillRegistry

DOMAIN = """
(define (domain fetch)
  (:requirements :strips :typing)
  (:types room item)
  (:predicates (robot-in ?r - room) (in ?i - item ?r - room) (holding ?i - item)
               (gripper-free) (passage ?a - room ?b - room))
  (:action go :parameters (?from ?to - room)
    :precondition (and (robot-in ?from) (passage ?from ?to))
    :effect (and (robot-in ?to) (not (robot-in ?from))))
  (:action take :parameters (?i - item ?r - room)
    :precondition (and (robot-in ?r) (in ?i ?r) (gripper-free))
    :effect (and (holding ?i) (not (in ?i ?r)) (not (gripper-free))))
  (:action put :parameters (?i - item ?r - room)
    :precondition (and (robot-in ?r) (holding ?i))
    :effect (and (in ?i ?r) (gripper-free) (not (holding ?i)))))
"""


def build_problem() -> KnowledgeBase:
    kb = KnowledgeBase.from_text(DOMAIN, name="fetch-cup")
    for room in ("hall", "kitchen", "office"):
        kb.add_instance(room, "room")
    kb.add_instance("cup", "item")
    kb.add_facts(["(robot-in hall)", "(gripper-free)", "(in cup kitchen)"])
    for a, b in (("hall", "kitchen"), ("hall", "office")):
        kb.add_facts([f"(passage {a} {b})", f"(passage {b} {a})"])
    kb.set_goal("(and (in cup office))")
    try:
        kb.add_fact("(robot-at kitchen)")
    except KnowledgeError as refusal:
        print(f"refused: {refusal}")
    return kb


def build_skills(kb: KnowledgeBase) -> SkillRegistry:
    """Skills that succeed; entering the kitchen, the camera sees a mug."""
    skills = SkillRegistry()
    outcomes = ["succeeded", "aborted", "preempted"]

    @skills.register("go")
    def go(src: str, dst: str) -> smach.State:
        def drive(ud: smach.UserData) -> str:
            print(f"robot: {src} -> {dst}")
            if dst == "kitchen" and "mug" not in kb.instances:
                kb.add_instance("mug", "item", source="perception")
                kb.add_fact("(in mug kitchen)", source="perception")
                kb.add_goal("(in mug office)", source="operator")
            return "succeeded"

        return smach.CBState(drive, outcomes=outcomes)

    for action in ("take", "put"):

        @skills.register(action)
        def hand(item: str, room: str, verb: str = action) -> smach.State:
            def act(ud: smach.UserData) -> str:
                print(f"robot: {verb} {item} in {room}")
                return "succeeded"

            return smach.CBState(act, outcomes=outcomes)

    return skills


def main() -> int:
    kb = build_problem()
    print(kb.problem_pddl(), end="")
    executive = Executive(kb.task(), build_skills(kb), "fast-downward", knowledge=kb)
    outcome = executive.execute()
    report = executive.report
    for decision in report.decisions:
        print(f"decision: {decision['decision']}: {decision['reason']}")
    print(f"executed: {' '.join(report.executed)}")
    goal = " ".join(f"({' '.join(atom)})" for atom in kb.goal)
    print(f"outcome: {outcome}; goal {goal}; knowledge base version {kb.version}")
    delivered = {("in", "cup", "office"), ("in", "mug", "office")} <= kb.facts
    return 0 if outcome == "succeeded" and delivered else 1


if __name__ == "__main__":
    sys.exit(main())
