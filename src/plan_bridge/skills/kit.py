"""Building blocks for writing skills: small states, skill machines, observations, routes.

A skill is a SMACH machine built for one plan step (see :mod:`plan_bridge.skills.registry`). Most
skills are made of the same few pieces, which this module provides:

- :class:`RobotState`: a state acting on the robot (or its simulated world) that answers a
  preempt request before it acts; subclasses write :meth:`RobotState.act`,
- :class:`WorldCall`: one call to the robot, its result named by two outcomes,
- :class:`Report`: a state that reports facts it computes from userdata,
- :func:`skill_machine`: the machine of one skill, its parameters bound from the plan step
  (or read as input keys when a hand-written machine runs it), writing ``observations``,
- :func:`observe` and :func:`fact`: add facts seen true or false to ``observations``,
- :func:`fewest_hops` and :func:`shortest_route`: routes on a map of places, for
  navigation skills and hand-written baselines.

Everything here is deterministic: nothing draws random numbers, and routes are chosen the
same way every time for the same map.
"""

from __future__ import annotations

import heapq
from collections import deque
from collections.abc import Callable, Hashable, Iterable, Mapping
from typing import Any, Generic, TypeVar

import smach
from plan_bridge.pddl.task import FactLike
from plan_bridge.skills.registry import OBSERVATIONS_KEY, REQUIRED_OUTCOMES

__all__ = [
    "SKILL_OUTCOMES",
    "Report",
    "RobotState",
    "WorldCall",
    "fact",
    "fewest_hops",
    "observe",
    "shortest_route",
    "skill_machine",
]

#: The outcomes of a skill machine: ``succeeded``, ``aborted``, ``preempted``.
SKILL_OUTCOMES: tuple[str, ...] = REQUIRED_OUTCOMES

W = TypeVar("W")
N = TypeVar("N", bound=Hashable)
V = TypeVar("V")


def fact(*words: str) -> str:
    """A ground fact as PDDL text: ``fact("at", "pr2", "kitchen")`` is ``"(at pr2 kitchen)"``."""
    return "(" + " ".join(words) + ")"


def observe(ud: smach.UserData, *pairs: tuple[FactLike, bool]) -> None:
    """Add facts seen true or false to ``ud.observations``.

    Facts are tuples or PDDL text; a fact seen again replaces what was seen before. The
    mapping is copied, not changed in place, so a machine that already handed its
    observations on never sees them change.
    """
    seen: dict[Any, bool] = dict(ud[OBSERVATIONS_KEY])
    seen.update(pairs)
    ud[OBSERVATIONS_KEY] = seen


class RobotState(smach.State, Generic[W]):
    """A state acting on ``world`` (the robot or its simulation); subclasses write :meth:`act`.

    It adds the outcome ``preempted`` to ``outcomes`` and returns it, without acting, when
    a preempt was requested before it started. By default it can read and write
    ``observations`` (see :func:`observe`); pass ``io_keys=()`` for a state that reports
    nothing.
    """

    def __init__(
        self,
        world: W,
        outcomes: Iterable[str],
        *,
        input_keys: Iterable[str] = (),
        output_keys: Iterable[str] = (),
        io_keys: Iterable[str] = (OBSERVATIONS_KEY,),
    ) -> None:
        super().__init__(
            outcomes=[*outcomes, "preempted"],
            input_keys=list(input_keys),
            output_keys=list(output_keys),
            io_keys=list(io_keys),
        )
        self.world = world

    def execute(self, ud: smach.UserData) -> str:
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        return self.act(ud)

    def act(self, ud: smach.UserData) -> str:
        """Do the state's work and return one of its outcomes."""
        raise NotImplementedError(f"{type(self).__name__} must implement act()")


class WorldCall(smach.State):
    """One call to the robot, named by its result: ``ok`` if ``call(ud)`` is true, else ``failed``.

    ``WorldCall(lambda ud: world.grasp_handle(ud.door), ok="grasped", failed="slipped",
    input_keys=["door"])``. With ``preemptable`` (the default) it also has the outcome
    ``preempted``, returned without calling when a preempt was requested before it started.
    """

    def __init__(
        self,
        call: Callable[[smach.UserData], object],
        *,
        ok: str,
        failed: str,
        input_keys: Iterable[str] = (),
        preemptable: bool = True,
    ) -> None:
        outcomes = [ok, failed, "preempted"] if preemptable else [ok, failed]
        super().__init__(outcomes=outcomes, input_keys=list(input_keys))
        self.call = call
        self.ok = ok
        self.failed = failed
        self.preemptable = preemptable

    def execute(self, ud: smach.UserData) -> str:
        if self.preemptable and self.preempt_requested():
            self.service_preempt()
            return "preempted"
        return self.ok if self.call(ud) else self.failed


class Report(smach.State):
    """Add the facts ``seen(ud)`` returns ({fact: true/false}) to ``observations``.

    It always returns ``outcome``: a machine reports what it found before it ends, e.g.
    ``Report(lambda ud: {fact("unlocked", ud.door): False}, "locked", ["door"])``.
    """

    def __init__(
        self,
        seen: Callable[[smach.UserData], Mapping[Any, bool]],
        outcome: str = "reported",
        input_keys: Iterable[str] = (),
    ) -> None:
        super().__init__(
            outcomes=[outcome], input_keys=list(input_keys), io_keys=[OBSERVATIONS_KEY]
        )
        self.seen = seen
        self.outcome = outcome

    def execute(self, ud: smach.UserData) -> str:
        observe(ud, *self.seen(ud).items())
        return self.outcome


def _clear_observations(ud: smach.UserData, initial_states: list[str]) -> None:
    ud[OBSERVATIONS_KEY] = {}


def skill_machine(
    keys: Iterable[str] = (),
    bind: Mapping[str, Any] | None = None,
    *,
    outcomes: Iterable[str] = SKILL_OUTCOMES,
) -> smach.StateMachine:
    """The (still empty) StateMachine of one skill, reading ``keys`` and writing ``observations``.

    With ``bind`` (the values of a plan step's parameters) the keys are set in the
    machine's own userdata; every key must have a value, and without ``keys`` all of
    ``bind`` is set. Without ``bind`` the keys are input keys instead, which a
    hand-written machine running the skill feeds through remapping.

    ``observations`` is emptied at the start of every run, so that a machine run more
    than once (a hand-written baseline reusing it) never reports facts of an earlier run.
    """
    names = list(keys)
    if bind is not None and not names:
        names = list(bind)
    sm = smach.StateMachine(
        outcomes=list(outcomes),
        input_keys=[] if bind is not None else names,
        output_keys=[OBSERVATIONS_KEY],
    )
    if bind is not None:
        missing = [k for k in names if k not in bind]
        if missing:
            raise ValueError(f"skill machine needs values for {missing}")
        for key in names:
            sm.userdata[key] = bind[key]
    sm.userdata[OBSERVATIONS_KEY] = {}
    sm.register_start_cb(_clear_observations)
    return sm


def fewest_hops(
    start: N, goal: N, exits: Callable[[N], Iterable[tuple[N, V]]]
) -> list[tuple[N, N, V]] | None:
    """A route from ``start`` to ``goal`` with the fewest legs, or None if there is none.

    ``exits(place)`` gives the places one leg away, each with what the leg goes through
    (a door, a passage, None...): ``(place, via)`` pairs. The route is a list of legs
    ``(from, to, via)``, empty when ``start`` is ``goal``. The search is breadth first
    and tries the exits in the order given, so of several equally short routes it
    always returns the same one.
    """
    previous: dict[N, tuple[N, N, V] | None] = {start: None}
    queue = deque([start])
    while queue:
        here = queue.popleft()
        if here == goal:
            legs: list[tuple[N, N, V]] = []
            while (leg := previous[here]) is not None:
                legs.append(leg)
                here = leg[0]
            return legs[::-1]
        for there, via in exits(here):
            if there not in previous:
                previous[there] = (here, there, via)
                queue.append(there)
    return None


def shortest_route(
    start: str, goal: str, exits: Callable[[str], Iterable[tuple[str, float]]]
) -> list[str] | None:
    """The shortest route (by total length) from ``start`` to ``goal``, or None.

    ``exits(place)`` gives ``(place, length)`` for each place one leg away. The route
    lists the places from ``start`` to ``goal``, both included. Of several equally
    long routes it returns the one whose list of places sorts first, whatever the
    order of the exits.
    """
    queue: list[tuple[float, list[str]]] = [(0.0, [start])]
    done: set[str] = set()
    while queue:
        length, route = heapq.heappop(queue)
        here = route[-1]
        if here == goal:
            return route
        if here in done:
            continue
        done.add(here)
        for there, leg in exits(here):
            if there not in done:
                heapq.heappush(queue, (length + leg, [*route, there]))
    return None
