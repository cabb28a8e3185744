"""SMACH skills over pyrobosim's robot API, one per action of the robosim domain.

Every skill is a small StateMachine acting on a robot's :class:`~.body.Body` (in a
:class:`~.world.RobosimWorld` of this process, or of the world's process when the robot
runs as a process of its own):

* ``navigate``: ``PLAN`` (the map's route over the hallways the robots have not seen
  closed) -> ``DRIVE`` (leg by leg with pyrobosim's path executor: inside rooms, and
  through hallways along their centre lines; a hallway found closed at its door ends
  the drive there) -> ``LOOK``;
* ``cross``: ``PLAN`` (the hallway's centre line, refused when the hallway is closed)
  -> ``DRIVE`` -> ``LOOK``;
* ``pick``, ``place``, ``open``, ``close``, ``detect``, ``search``, ``charge``: ``ACT`` ->
  ``LOOK`` (``search`` succeeds when the object is at the place, and fails when not).

``PLAN``, ``DRIVE`` and ``ACT`` keep pyrobosim's ``ExecutionStatus`` in the userdata
(``status``, ``message``); ``LOOK`` reports what the robot sees afterwards
(``observations``) and maps the status to the skill's outcome: SUCCESS ->
``succeeded``, CANCELED -> ``preempted``, anything else (PRECONDITION_FAILURE,
PLANNING_FAILURE, EXECUTION_FAILURE, POSTCONDITION_FAILURE, INVALID_ACTION) ->
``aborted``. A preempt cancels the robot's running action (``robot.cancel_actions()``).
"""

from __future__ import annotations

from collections.abc import Callable

import smach
from plan_bridge.robosim.body import Body, WorldBody
from plan_bridge.robosim.results import ActionResult
from plan_bridge.robosim.world import RobosimWorld
from plan_bridge.skills.kit import SKILL_OUTCOMES, skill_machine
from plan_bridge.skills.registry import OBSERVATIONS_KEY, SkillRegistry

__all__ = ["ACTIONS", "robosim_skills", "skill_for"]

#: The actions of the robosim domain and their parameters.
ACTIONS: dict[str, tuple[str, ...]] = {
    "navigate": ("robot", "origin", "target"),
    "cross": ("robot", "origin", "target", "hallway"),
    "pick": ("robot", "object", "place", "location"),
    "place": ("robot", "object", "place", "location"),
    "open": ("robot", "gate", "place"),
    "close": ("robot", "gate", "place"),
    "detect": ("robot", "place", "location"),
    "search": ("robot", "object", "place", "location"),
    "charge": ("robot", "place", "location"),
}
_RESULT_KEYS = ["status", "message"]


class _Step(smach.State):
    """A state that runs ``work(preempted)`` and keeps its result in the userdata."""

    def __init__(
        self,
        work: Callable[[smach.UserData, Callable[[], bool]], ActionResult],
        outcomes: list[str],
        choose: Callable[[ActionResult], str],
        input_keys: tuple[str, ...] = (),
        output_keys: tuple[str, ...] = (),
    ) -> None:
        super().__init__(
            outcomes=outcomes,
            input_keys=list(input_keys),
            output_keys=[*_RESULT_KEYS, *output_keys],
        )
        self.work = work
        self.choose = choose

    def execute(self, ud: smach.UserData) -> str:
        result = self.work(ud, self.preempt_requested)
        ud.status, ud.message = result.status, result.message
        return self.choose(result)


class _Look(smach.State):
    """Report what the robot sees; the skill's outcome from the action's status."""

    def __init__(self, body: Body, robot: str, about: tuple[str, ...]) -> None:
        super().__init__(
            outcomes=list(SKILL_OUTCOMES), input_keys=_RESULT_KEYS, io_keys=[OBSERVATIONS_KEY]
        )
        self.body = body
        self.robot = robot
        self.about = about

    def execute(self, ud: smach.UserData) -> str:
        ud[OBSERVATIONS_KEY] = dict(self.body.look(self.robot, self.about))
        outcome = ActionResult(ud.status, ud.message).outcome
        if ud.status != "SUCCESS":
            smach.logdebug(f"{self.robot}: {ud.status}: {ud.message}")
        if outcome == "preempted" or self.preempt_requested():
            self.service_preempt()
            return "preempted"
        return outcome


def skill_for(world: RobosimWorld | Body, action: str, *args: str) -> smach.StateMachine:
    """The skill machine of one step: ``skill_for(world, "pick", "robot", "apple0", ...)``
    (``world``: a :class:`~.world.RobosimWorld`, or the :class:`~.body.Body` to act with)."""
    names = ACTIONS[action]
    robot = args[0]
    if isinstance(world, RobosimWorld):
        world.robot(robot)  # KeyError now for a robot the world does not have
    body: Body = WorldBody(world) if isinstance(world, RobosimWorld) else world
    sm = skill_machine(bind=dict(zip(names, args, strict=True)))
    look = _Look(body, robot, tuple(args))
    with sm:
        if action in ("navigate", "cross"):

            def plan(ud: smach.UserData, preempted: Callable[[], bool]) -> ActionResult:
                if preempted():
                    return ActionResult("CANCELED", "preempted before planning")
                ud.path, result = body.plan(robot, action, args)
                return result

            def drive(ud: smach.UserData, preempted: Callable[[], bool]) -> ActionResult:
                return body.drive(robot, action, args, ud.path, preempted)

            smach.StateMachine.add(
                "PLAN",
                _Step(
                    plan,
                    ["planned", "arrived", "failed"],
                    lambda r: (
                        "failed" if r.status != "SUCCESS" else "arrived" if r.message else "planned"
                    ),
                    output_keys=("path",),
                ),
                transitions={"planned": "DRIVE", "arrived": "LOOK", "failed": "LOOK"},
            )
            smach.StateMachine.add(
                "DRIVE",
                _Step(drive, ["done"], lambda r: "done", input_keys=("path",)),
                transitions={"done": "LOOK"},
            )
        else:

            def work(ud: smach.UserData, preempted: Callable[[], bool]) -> ActionResult:
                return body.act(robot, action, args, preempted)

            smach.StateMachine.add(
                "ACT", _Step(work, ["done"], lambda r: "done"), transitions={"done": "LOOK"}
            )
        smach.StateMachine.add("LOOK", look)
    return sm


def robosim_skills(
    world: RobosimWorld, registry: SkillRegistry | None = None, *, body: Body | None = None
) -> SkillRegistry:
    """A registry of simulated skills acting on ``world`` for every robosim action
    (through ``body``: default the world's own robots, :class:`~.body.WorldBody`)."""
    registry = registry or SkillRegistry(simulated=True)
    acting: Body = body or WorldBody(world)
    for action in ACTIONS:

        def factory(*args: str, _action: str = action) -> smach.State:
            return skill_for(acting, _action, *args)

        factory.__qualname__ = f"skill_for[{action}]"
        registry.add(action, factory, simulated=True)
    registry.world = world
    return registry
