"""timed_courier written by hand: one SMACH machine with explicit recovery, no planner.

The author read the building plan and wrote, for every parcel of the goal, the trip
the courier makes: recharge on the pad where it starts (a battery drains faster than
the model says on some days, so always start full), drive or pass fire doors room by
room to the parcel (the shortest route), grab it, the same route back, hand it over.
A fire door is crossed while the helper holds it, as a Concurrence of the helper's
``hold-door`` and the courier's ``pass-door``; the helper keeps holding until the
courier is through (a courier running late would otherwise meet a closing door).
Recoveries anticipated: every action and every door crossing is tried up to three
times (an action that fails halfway leaves the robot where it began). A fourth failure,
a helper that stands at neither side of a door, or a battery that runs out on the way
ends the mission ``aborted``. The machine, per parcel ``n``::

    RECHARGE_n -> [GO_n_k: DRIVE (x3) | CROSS (Concurrence HOLD || PASS, x3)]...
      -> GRAB_n (x3) -> [BACK_n_k ...] -> HAND_OVER_n (x3) -> next parcel | succeeded

Durations are the model's (``metres / speed`` for a drive); the world may make an
action last longer, which the machine simply waits for.
"""

from __future__ import annotations

import threading
from collections import deque
from typing import Any

import smach
from plan_bridge.execution.timed_world import TimedSkill
from plan_bridge.missions.mission import ScriptedMission
from plan_bridge.pddl.task import PlanningTask
from plan_bridge.planning.planner import PlanStep

from .skills import CourierWorld

__all__ = ["scripted"]

ATTEMPTS = 3
#: Planned durations (plan seconds) of the actions that have a fixed one in the domain.
DURATIONS = {"pass-door": 3.0, "hold-door": 5.0, "grab": 2.0, "hand-over": 2.0, "recharge": 2.0}


class TimedAction(smach.State):
    """Play one ground action in the world, up to :data:`ATTEMPTS` times.

    ``hold_until``: keep holding (do not end) until that event is set, at most
    ``hold_limit`` wall seconds. ``done``: set when this action ends, however it ends.
    """

    def __init__(
        self,
        world: CourierWorld,
        step: PlanStep,
        duration: float,
        *,
        hold_until: threading.Event | None = None,
        done: threading.Event | None = None,
    ) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])
        self.world = world
        self.step = step
        self.duration = duration
        self.hold_until = hold_until
        self.done = done

    def _end_ready(self) -> None:
        if self.hold_until is not None:
            # Four times the courier's slowest crossing, in wall seconds (at least 1 s).
            self.hold_until.wait(max(1.0, 4 * DURATIONS["pass-door"] * self.world.time_scale))

    def execute(self, ud: smach.UserData) -> str:
        attempts = 1 if self.hold_until is not None or self.done is not None else ATTEMPTS
        outcome = "aborted"
        try:
            for _ in range(attempts):
                inner = smach.UserData()
                inner.duration = self.duration
                inner.end_ready = self._end_ready
                inner.begun = lambda: None  # the script orders its crossings itself
                skill = TimedSkill(self.world, self.step)
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                outcome = skill.execute(inner)
                if outcome != "aborted":
                    return outcome
            return outcome
        finally:
            if self.done is not None:
                self.done.set()


def _crossing(world: CourierWorld, courier: str, helper_at: str, a: str, b: str) -> smach.State:
    """The helper holds the fire door a-b while the courier passes from a to b."""
    through = threading.Event()
    side = a if helper_at == a else b
    other = b if side == a else a
    cross = smach.Concurrence(
        outcomes=["succeeded", "aborted", "preempted"],
        default_outcome="aborted",
        outcome_map={"succeeded": {"HOLD": "succeeded", "PASS": "succeeded"}},
    )
    with cross:
        smach.Concurrence.add(
            "HOLD",
            TimedAction(
                world,
                PlanStep("hold-door", ("helper", side, other)),
                DURATIONS["hold-door"],
                hold_until=through,
            ),
        )
        smach.Concurrence.add(
            "PASS",
            TimedAction(
                world, PlanStep("pass-door", (courier, a, b)), DURATIONS["pass-door"], done=through
            ),
        )
    retried = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    tries = {"n": 0}

    @smach.cb_interface(outcomes=["again", "give_up"])
    def again(ud: smach.UserData) -> str:
        tries["n"] += 1
        through.clear()
        return "again" if tries["n"] < ATTEMPTS else "give_up"

    @smach.cb_interface(outcomes=["go"])
    def start(ud: smach.UserData) -> str:
        tries["n"] = 0
        through.clear()
        return "go"

    with retried:
        smach.StateMachine.add("START", smach.CBState(start), {"go": "CROSS"})
        smach.StateMachine.add("CROSS", cross, {"aborted": "AGAIN"})
        smach.StateMachine.add(
            "AGAIN", smach.CBState(again), {"again": "CROSS", "give_up": "aborted"}
        )
    return retried


def _route(task: PlanningTask, start: str, goal: str) -> list[tuple[str, str, bool]]:
    """The fewest joints from ``start`` to ``goal``: (from, to, through a fire door?)."""
    links: dict[str, list[tuple[str, bool]]] = {}
    for fact in task.initial_facts:
        if fact[0] in ("corridor", "fire-door"):
            links.setdefault(fact[1], []).append((fact[2], fact[0] == "fire-door"))
    before: dict[str, tuple[str, bool] | None] = {start: None}
    frontier = deque([start])
    while frontier:
        room = frontier.popleft()
        for nxt, door in sorted(links.get(room, [])):
            if nxt not in before:
                before[nxt] = (room, door)
                frontier.append(nxt)
    if goal not in before:
        raise ValueError(f"timed_courier scripted: no route from {start} to {goal}")
    legs: list[tuple[str, str, bool]] = []
    room = goal
    while (link := before[room]) is not None:
        legs.append((link[0], room, link[1]))
        room = link[0]
    return legs[::-1]


def scripted(task: PlanningTask, *, seed: int, fail_rate: float) -> ScriptedMission:
    """The whole mission as one hand-written machine acting on a fresh world."""
    world = CourierWorld(task, seed=seed, fail_rate=fail_rate)
    at = {f[1]: f[2] for f in task.initial_facts if f[0] == "at"}
    courier, helper_at = "courier", at["helper"]
    parcel_at = {f[1]: f[2] for f in task.initial_facts if f[0] == "parcel-at"}
    pads = {f[1] for f in task.initial_facts if f[0] == "charging-pad"}
    deliveries = [(g[1], g[2]) for g in task.goal_facts if g[0] == "parcel-at"]
    mission = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    numbers: dict[str, float] = world.values
    names: list[tuple[str, smach.State]] = []

    def add(name: str, action: str, arguments: tuple[str, ...], duration: float) -> None:
        names.append((name, TimedAction(world, PlanStep(action, arguments), duration)))

    def add_route(prefix: str, start: str, goal: str) -> None:
        for k, (a, b, door) in enumerate(_route(task, start, goal), start=1):
            if not door:
                duration = numbers[f"(metres {a} {b})"] / numbers[f"(speed {courier})"]
                add(f"{prefix}_{k}", "drive", (courier, a, b), duration)
            elif helper_at in (a, b):
                names.append((f"{prefix}_{k}", _crossing(world, courier, helper_at, a, b)))
            else:
                raise ValueError(
                    f"timed_courier scripted: the helper ({helper_at}) stands at neither "
                    f"side of the fire door {a}-{b}"
                )

    room = at[courier]
    for n, (parcel, destination) in enumerate(deliveries, start=1):
        if room in pads:
            add(f"RECHARGE_{n}", "recharge", (courier, room), DURATIONS["recharge"])
        add_route(f"GO_{n}", room, parcel_at[parcel])
        add(f"GRAB_{n}", "grab", (courier, parcel, parcel_at[parcel]), DURATIONS["grab"])
        add_route(f"BACK_{n}", parcel_at[parcel], destination)
        add(f"HAND_OVER_{n}", "hand-over", (courier, parcel, destination), DURATIONS["hand-over"])
        room = destination
    with mission:
        for i, (name, state) in enumerate(names):
            following = names[i + 1][0] if i + 1 < len(names) else "succeeded"
            smach.StateMachine.add(name, state, {"succeeded": following})
    extra: dict[str, Any] = {"courier": courier}
    return ScriptedMission(mission, world, extra)
