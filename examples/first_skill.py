"""Your first skill: one hand-written SMACH skill in a planned mission, the rest simulated.

The fetch_drink domain's ``navigate`` runs as the skill below (where a robot driver
would be called); every other action runs in the simulated world, which learns what
``navigate`` did when it succeeds. Run it: ``python examples/first_skill.py``.
"""

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import load_task
from plan_bridge.skills.registry import SkillRegistry

task = load_task("domains/fetch_drink/domain.pddl", "domains/fetch_drink/problems/p01.pddl")
skills = SkillRegistry()


@skills.register("navigate")
def navigate(robot: str, origin: str, destination: str) -> smach.State:
    def drive(ud: smach.UserData) -> str:
        print(f"{robot}: driving {origin} -> {destination}")  # call your robot here
        ud.observations = {f"(at {robot} {destination})": True}  # what it saw
        return "succeeded"

    return smach.CBState(drive, outcomes=["succeeded", "aborted", "preempted"],
                         output_keys=["observations"])  # fmt: skip


world = SimulatedWorld(task, seed=1, fail_rate=0.2)  # faults in the simulated actions
mission = Executive(task, symbolic_skills(world, skills))  # planner "auto", as the CLI
print("outcome:", mission.execute(), "-", mission.report.explanation)
print("executed:", *mission.report.executed, sep="\n  ")
raise SystemExit(0 if mission.report.goal_reached else 1)
