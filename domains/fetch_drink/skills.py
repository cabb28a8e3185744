"""The fetch_drink skills: one hand-written SMACH machine per PDDL action.

Each factory builds a fresh machine for one plan step. The machines act on the
simulated world through its small methods (``drive``, ``look_for``, ``grasp``...)
and report what they saw as ``observations`` so the executive's belief follows the
world: a blocked corridor, a drink found on another shelf, a fridge that stayed shut.

The small states below are shared with the scripted baseline (scripted.py): both
missions use the same motor skills and differ only in who decides what to do next.
"""

from __future__ import annotations

import smach
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.skills.kit import Report, RobotState, fact, observe, skill_machine
from plan_bridge.skills.registry import SkillRegistry

from .world import CONGESTION_WAIT, FetchDrinkWorld

__all__ = [
    "CheckFridge",
    "DetectDrink",
    "Drive",
    "build_skills",
    "close_fridge_machine",
    "drive_machine",
    "grasp_machine",
    "hand_over_machine",
    "navigate_machine",
    "open_fridge_machine",
    "pick_machine",
    "setup",
]

#: Attempts of the local retries (a robotics engineer's usual "try three times").
DRIVE_ATTEMPTS = 4
OPEN_ATTEMPTS = 3
GRASP_ATTEMPTS = 3
CLOSE_ATTEMPTS = 2


# -- building blocks -------------------------------------------------------------------


class Drive(RobotState[FetchDrinkWorld]):
    """Drive one corridor, ``origin`` -> ``destination``."""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(
            world,
            ["arrived", "congested", "blocked"],
            input_keys=["robot", "origin", "destination"],
            io_keys=(),
        )

    def act(self, ud: smach.UserData) -> str:
        return self.world.drive(ud.robot, ud.origin, ud.destination)


class WaitForPassage(smach.State):
    """Give a person in the corridor time to move on (simulated seconds)."""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["waited"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        self.world.wait(CONGESTION_WAIT)
        return "waited"


class Pause(smach.State):
    """A motion without failure modes worth simulating (arm to pre-grasp, look up)."""

    def __init__(self, world: FetchDrinkWorld, seconds: float, outcome: str = "done") -> None:
        super().__init__(outcomes=[outcome])
        self.world = world
        self.seconds = seconds
        self.outcome = outcome

    def execute(self, ud: smach.UserData) -> str:
        self.world.wait(self.seconds)
        return self.outcome


class GraspHandle(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["grasped", "slipped"], input_keys=["fridge"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        return "grasped" if self.world.grasp_fridge_handle(ud.fridge) else "slipped"


class PullDoor(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["opened", "stuck"], input_keys=["fridge"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        return "opened" if self.world.pull_fridge_door(ud.fridge) else "stuck"


class PushDoor(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["pushed", "rebounded"], input_keys=["fridge"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        return "pushed" if self.world.push_fridge_door(ud.fridge) else "rebounded"


class CheckFridge(smach.State):
    """Look at the fridge door and report whether it is open."""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(
            outcomes=["open", "closed"], input_keys=["fridge"], io_keys=["observations"]
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        is_open = self.world.holds("fridge-open", ud.fridge)
        observe(
            ud,
            (fact("fridge-open", ud.fridge), is_open),
            (fact("fridge-closed", ud.fridge), not is_open),
        )
        return "open" if is_open else "closed"


class DetectDrink(smach.State):
    """Look into the open fridge for the drink; report where it really stands.

    ``seen``: on the expected shelf. ``elsewhere``: on another shelf (written to
    ``found_shelf``). ``missing``: on no shelf of this fridge.
    """

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(
            outcomes=["seen", "elsewhere", "missing"],
            input_keys=["drink", "shelf", "fridge"],
            output_keys=["found_shelf"],
            io_keys=["observations"],
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        found = self.world.look_for(ud.drink, ud.fridge)
        ud.found_shelf = found
        observe(
            ud,
            *(
                (fact("on", ud.drink, shelf), shelf == found)
                for shelf in self.world.shelves_of(ud.fridge)
            ),
        )
        if found is None:
            return "missing"
        return "seen" if found == ud.shelf else "elsewhere"


class CloseGripper(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["closed"], input_keys=["robot", "drink", "shelf"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        self.world.grasp(ud.robot, ud.drink, ud.shelf)
        return "closed"


class VerifyGrasp(smach.State):
    """Read the gripper's finger gap: is the drink between the fingers after lifting?"""

    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["held", "slipped"], input_keys=["robot", "drink"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        return "held" if self.world.holds("holding", ud.robot, ud.drink) else "slipped"


class FindPerson(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(
            outcomes=["found", "absent"],
            input_keys=["person", "place"],
            io_keys=["observations"],
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        self.world.wait(2.0)
        present = self.world.holds("person-at", ud.person, ud.place)
        seen = {fact("person-at", ud.person, ud.place): present}
        if not present:
            # Not here: call the person and ask where they are, so a new plan can go there.
            actual = self.world.where_is(ud.person)
            if actual is not None:
                seen[fact("person-at", ud.person, actual)] = True
        observe(ud, *seen.items())
        return "found" if present else "absent"


class OfferDrink(smach.State):
    def __init__(self, world: FetchDrinkWorld) -> None:
        super().__init__(outcomes=["taken", "refused"], input_keys=["robot", "drink", "person"])
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        return "taken" if self.world.hand_over(ud.robot, ud.drink, ud.person) else "refused"


# -- skills: one machine per action -------------------------------------------------------


def drive_machine(world: FetchDrinkWorld) -> smach.Retry:
    """Retry x4 [ DRIVE --congested--> WAIT_FOR_PASSAGE ]: arrived / congested / blocked.

    People move on, so a congested corridor is tried again after a pause; a static
    obstacle does not, so ``blocked`` ends the retries at once.
    """
    attempt = smach.StateMachine(
        outcomes=["arrived", "congested", "blocked", "preempted"],
        input_keys=["robot", "origin", "destination"],
    )
    with attempt:
        smach.StateMachine.add("DRIVE", Drive(world), {"congested": "WAIT_FOR_PASSAGE"})
        smach.StateMachine.add("WAIT_FOR_PASSAGE", WaitForPassage(world), {"waited": "congested"})
    return smach.Retry.wrap(
        "ATTEMPT", attempt, attempts=DRIVE_ATTEMPTS, retry_outcomes=["congested"]
    )


def navigate_machine(
    world: FetchDrinkWorld, robot: str, origin: str, destination: str
) -> smach.StateMachine:
    """DRIVE (retried while people are in the way) -> REPORT_BLOCKED on a static obstacle.

    ::

        DRIVE = Retry x4 [ DRIVE --congested--> WAIT_FOR_PASSAGE ]
        DRIVE --arrived--> succeeded
              --blocked--> REPORT_BLOCKED (clear from to: false) --> aborted
              --congested--> aborted (still crowded: the executive may retry the step)
    """
    sm = skill_machine(bind={"robot": robot, "from_place": origin, "to_place": destination})
    with sm:
        smach.StateMachine.add(
            "DRIVE",
            drive_machine(world),
            transitions={
                "arrived": "succeeded",
                "blocked": "REPORT_BLOCKED",
                "congested": "aborted",
            },
            remapping={"origin": "from_place", "destination": "to_place"},
        )
        smach.StateMachine.add(
            "REPORT_BLOCKED",
            Report(
                lambda ud: {
                    fact("clear", ud.from_place, ud.to_place): False,
                    fact("clear", ud.to_place, ud.from_place): False,
                    fact("at", ud.robot, ud.from_place): True,
                },
                input_keys=["robot", "from_place", "to_place"],
            ),
            transitions={"reported": "aborted"},
        )
    return sm


def open_attempt(world: FetchDrinkWorld) -> smach.StateMachine:
    attempt = smach.StateMachine(outcomes=["opened", "failed"], input_keys=["fridge"])
    with attempt:
        smach.StateMachine.add(
            "GRASP_HANDLE", GraspHandle(world), {"grasped": "PULL_DOOR", "slipped": "failed"}
        )
        smach.StateMachine.add(
            "PULL_DOOR", PullDoor(world), {"opened": "opened", "stuck": "RELEASE_HANDLE"}
        )
        smach.StateMachine.add("RELEASE_HANDLE", Pause(world, 1.0), {"done": "failed"})
    return attempt


def open_fridge_machine(world: FetchDrinkWorld, robot: str, fridge: str) -> smach.StateMachine:
    """FIND_HANDLE -> OPEN (Retry x3 [GRASP_HANDLE -> PULL_DOOR]) -> CHECK_OPEN."""
    sm = skill_machine(bind={"robot": robot, "fridge": fridge})
    with sm:
        smach.StateMachine.add("FIND_HANDLE", Pause(world, 1.5, "found"), {"found": "OPEN"})
        smach.StateMachine.add(
            "OPEN",
            smach.Retry.wrap(
                "ATTEMPT", open_attempt(world), attempts=OPEN_ATTEMPTS, retry_outcomes=["failed"]
            ),
            transitions={"opened": "CHECK_OPEN", "failed": "CHECK_OPEN"},
        )
        smach.StateMachine.add(
            "CHECK_OPEN", CheckFridge(world), {"open": "succeeded", "closed": "aborted"}
        )
    return sm


def grasp_machine(world: FetchDrinkWorld) -> smach.Retry:
    """Retry x3 [ CLOSE_GRIPPER -> VERIFY_GRASP ]: outcomes held / slipped."""
    attempt = smach.StateMachine(
        outcomes=["held", "slipped"], input_keys=["robot", "drink", "shelf"]
    )
    with attempt:
        smach.StateMachine.add("CLOSE_GRIPPER", CloseGripper(world), {"closed": "VERIFY_GRASP"})
        smach.StateMachine.add("VERIFY_GRASP", VerifyGrasp(world))
    return smach.Retry.wrap("ATTEMPT", attempt, attempts=GRASP_ATTEMPTS, retry_outcomes=["slipped"])


def pick_machine(
    world: FetchDrinkWorld, robot: str, drink: str, shelf: str, fridge: str
) -> smach.StateMachine:
    """DETECT -> APPROACH -> GRASP (local retry) -> RETREAT.

    ::

        DETECT --seen--> APPROACH --> GRASP = Retry x3 [CLOSE_GRIPPER -> VERIFY_GRASP]
               --elsewhere/missing--> aborted   (observations say where the drink is)
        GRASP --held--> RETREAT --> succeeded
              --slipped--> REPORT_SLIP (still on the shelf, hand empty) --> aborted
    """
    sm = skill_machine(
        bind={"robot": robot, "drink": drink, "shelf": shelf, "fridge": fridge, "found_shelf": None}
    )
    with sm:
        smach.StateMachine.add(
            "DETECT",
            DetectDrink(world),
            transitions={"seen": "APPROACH", "elsewhere": "aborted", "missing": "aborted"},
        )
        smach.StateMachine.add("APPROACH", Pause(world, 3.0, "ready"), {"ready": "GRASP"})
        smach.StateMachine.add(
            "GRASP", grasp_machine(world), transitions={"held": "RETREAT", "slipped": "REPORT_SLIP"}
        )
        smach.StateMachine.add("RETREAT", Pause(world, 2.0), {"done": "succeeded"})
        smach.StateMachine.add(
            "REPORT_SLIP",
            Report(
                lambda ud: {
                    fact("on", ud.drink, ud.shelf): world.holds("on", ud.drink, ud.shelf),
                    fact("hand-empty", ud.robot): world.holds("hand-empty", ud.robot),
                },
                input_keys=["robot", "drink", "shelf"],
            ),
            transitions={"reported": "aborted"},
        )
    return sm


def close_fridge_machine(world: FetchDrinkWorld, robot: str, fridge: str) -> smach.StateMachine:
    """PUSH_DOOR (Retry x2 while it bounces back) -> CHECK_CLOSED."""
    sm = skill_machine(bind={"robot": robot, "fridge": fridge})
    with sm:
        smach.StateMachine.add(
            "PUSH_DOOR",
            smach.Retry.wrap(
                "PUSH", PushDoor(world), attempts=CLOSE_ATTEMPTS, retry_outcomes=["rebounded"]
            ),
            transitions={"pushed": "CHECK_CLOSED", "rebounded": "CHECK_CLOSED"},
        )
        smach.StateMachine.add(
            "CHECK_CLOSED", CheckFridge(world), {"closed": "succeeded", "open": "aborted"}
        )
    return sm


def hand_over_machine(
    world: FetchDrinkWorld, robot: str, drink: str, person: str, place: str
) -> smach.StateMachine:
    """FIND_PERSON -> OFFER (release when the person pulls) -> RETRACT."""
    sm = skill_machine(bind={"robot": robot, "drink": drink, "person": person, "place": place})
    with sm:
        smach.StateMachine.add(
            "FIND_PERSON", FindPerson(world), {"found": "OFFER", "absent": "aborted"}
        )
        smach.StateMachine.add(
            "OFFER", OfferDrink(world), {"taken": "RETRACT", "refused": "aborted"}
        )
        smach.StateMachine.add("RETRACT", Pause(world, 2.0), {"done": "succeeded"})
    return sm


def build_skills(world: FetchDrinkWorld) -> SkillRegistry:
    """The registry binding every action of domain.pddl to its machine."""
    skills = SkillRegistry(simulated=True)
    skills.add("navigate", lambda r, a, b: navigate_machine(world, r, a, b))
    skills.add("open-fridge", lambda r, f, p: open_fridge_machine(world, r, f))
    skills.add("pick-drink", lambda r, d, s, f, p: pick_machine(world, r, d, s, f))
    skills.add("close-fridge", lambda r, f, p: close_fridge_machine(world, r, f))
    skills.add("hand-over", lambda r, d, h, p: hand_over_machine(world, r, d, h, p))
    return skills


def setup(task: PlanningTask, *, seed: int, fail_rate: float, variant: str = "") -> MissionSetup:
    """The mission protocol of plan_bridge: skills acting on a fresh simulated world."""
    world = FetchDrinkWorld(task, seed=seed, fail_rate=fail_rate, variant=variant)
    return MissionSetup(skills=build_skills(world), world=world)
