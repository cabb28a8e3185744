"""The skill kit: robot states, world calls, reports, skill machines and routes."""

from __future__ import annotations

from pathlib import Path

import pytest

import smach
from plan_bridge.belief import normalise_observations
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.skills.kit import (
    SKILL_OUTCOMES,
    Report,
    RobotState,
    WorldCall,
    fact,
    fewest_hops,
    observe,
    shortest_route,
    skill_machine,
)
from plan_bridge.skills.registry import SkillRegistry

ROOMS = Path(__file__).parents[1] / "data" / "rooms"


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


class Counter:
    """A stand-in for a robot: counts what it is asked to do."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def wave(self, who: str) -> bool:
        self.calls.append(who)
        return who != "nobody"


class Wave(RobotState[Counter]):
    def __init__(self, robot: Counter) -> None:
        super().__init__(robot, ["waved", "ignored"], input_keys=["who"])

    def act(self, ud: smach.UserData) -> str:
        return "waved" if self.world.wave(ud.who) else "ignored"


def _run(state: smach.State, **userdata: object) -> tuple[str | None, smach.UserData]:
    """Run ``state`` alone in a machine whose userdata holds ``userdata``."""
    sm = smach.StateMachine(outcomes=[*state.get_registered_outcomes()])
    for key, value in userdata.items():
        sm.userdata[key] = value
    with sm:
        smach.StateMachine.add("STATE", state)
    return sm.execute(), sm.userdata


# -- facts and observations ------------------------------------------------------------------
def test_fact_writes_a_ground_fact_as_pddl_text() -> None:
    assert fact("at", "pr2", "kitchen") == "(at pr2 kitchen)"
    assert normalise_observations({fact("free", "pr2"): True}) == [(("free", "pr2"), True)]


def test_observe_adds_facts_and_never_changes_a_mapping_already_handed_on() -> None:
    ud = smach.UserData({"observations": {}})
    observe(ud, (("at", "r", "a"), True))
    handed_on = ud.observations
    observe(ud, ("(at r a)", False), (("at", "r", "a"), False), (("at", "r", "b"), True))
    assert handed_on == {("at", "r", "a"): True}
    assert ud.observations == {
        ("at", "r", "a"): False,
        "(at r a)": False,
        ("at", "r", "b"): True,
    }


# -- states ----------------------------------------------------------------------------------
def test_robot_state_acts_on_its_world_and_can_also_be_preempted() -> None:
    robot = Counter()
    state = Wave(robot)
    assert state.get_registered_outcomes() == ("waved", "ignored", "preempted")
    assert set(state.get_registered_input_keys()) == {"who", "observations"}
    assert _run(state, who="alice", observations={})[0] == "waved"
    assert _run(state, who="nobody", observations={})[0] == "ignored"
    assert robot.calls == ["alice", "nobody"]


def test_robot_state_returns_preempted_without_acting_when_preempted_before_it_starts() -> None:
    robot = Counter()
    state = Wave(robot)
    state.request_preempt()
    assert state.execute(smach.UserData({"who": "alice"})) == "preempted"
    assert robot.calls == []
    assert not state.preempt_requested()  # the request was serviced


def test_robot_state_without_io_keys_reports_nothing() -> None:
    class Look(RobotState[Counter]):
        def __init__(self, robot: Counter) -> None:
            super().__init__(robot, ["seen"], output_keys=["where"], io_keys=())

        def act(self, ud: smach.UserData) -> str:
            ud.where = "here"
            return "seen"

    state = Look(Counter())
    assert state.get_registered_input_keys() == ()
    assert state.get_registered_output_keys() == ("where",)
    assert _run(state)[1].where == "here"


def test_robot_state_must_be_given_an_act_method() -> None:
    with pytest.raises(NotImplementedError, match="RobotState must implement act"):
        RobotState(Counter(), ["done"]).execute(smach.UserData())


def test_world_call_names_the_result_of_the_call() -> None:
    robot = Counter()
    state = WorldCall(
        lambda ud: robot.wave(ud.who), ok="waved", failed="ignored", input_keys=["who"]
    )
    assert state.get_registered_outcomes() == ("waved", "ignored", "preempted")
    assert _run(state, who="bob")[0] == "waved"
    assert _run(state, who="nobody")[0] == "ignored"
    state.request_preempt()
    assert state.execute(smach.UserData({"who": "carol"})) == "preempted"
    assert robot.calls == ["bob", "nobody"]


def test_world_call_that_is_not_preemptable_has_no_preempted_outcome_and_always_calls() -> None:
    robot = Counter()
    state = WorldCall(
        lambda ud: robot.wave(ud.who), ok="waved", failed="ignored", preemptable=False
    )
    assert state.get_registered_outcomes() == ("waved", "ignored")
    state.request_preempt()
    assert state.execute(smach.UserData({"who": "dave"})) == "waved"
    assert robot.calls == ["dave"]


def test_report_adds_what_it_computes_to_the_observations_and_returns_its_outcome() -> None:
    report = Report(lambda ud: {fact("open", ud.door): False}, "locked", ["door"])
    assert report.get_registered_outcomes() == ("locked",)
    outcome, ud = _run(report, door="d1", observations={"(seen d1)": True})
    assert outcome == "locked"
    assert ud.observations == {"(seen d1)": True, "(open d1)": False}
    assert Report(lambda ud: {}).get_registered_outcomes() == ("reported",)


# -- skill machines --------------------------------------------------------------------------
def _greet(robot: Counter, bind: dict[str, object] | None = None) -> smach.StateMachine:
    """A skill machine: WAVE, then REPORT what the robot saw."""
    sm = skill_machine(["who"], bind)
    with sm:
        smach.StateMachine.add("WAVE", Wave(robot), {"waved": "REPORT", "ignored": "aborted"})
        smach.StateMachine.add(
            "REPORT",
            Report(lambda ud: {fact("greeted", ud.who): True}, "succeeded", ["who"]),
        )
    return sm


def test_skill_machine_binds_a_plan_steps_parameters_in_its_own_userdata() -> None:
    sm = _greet(Counter(), {"who": "alice"})
    assert sm.get_registered_outcomes() == SKILL_OUTCOMES
    assert sm.get_registered_input_keys() == ()
    assert sm.get_registered_output_keys() == ("observations",)
    assert sm.execute() == "succeeded"
    assert sm.userdata.observations == {"(greeted alice)": True}


def test_skill_machine_binds_all_given_values_without_keys_and_refuses_missing_ones() -> None:
    sm = skill_machine(bind={"robot": "pr2", "room": "lab"}, outcomes=[*SKILL_OUTCOMES, "locked"])
    assert (sm.userdata.robot, sm.userdata.room, sm.userdata.observations) == ("pr2", "lab", {})
    assert "locked" in sm.get_registered_outcomes()
    with pytest.raises(ValueError, match=r"needs values for \['who'\]"):
        skill_machine(["who"], {"someone": "x"})


def test_skill_machine_without_values_reads_its_keys_from_the_machine_running_it() -> None:
    robot = Counter()
    greet = _greet(robot)
    assert set(greet.get_registered_input_keys()) == {"who"}
    outer = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    outer.userdata.guest = "bob"
    with outer:
        smach.StateMachine.add(
            "GREET",
            greet,
            {"succeeded": "done", "aborted": "failed"},
            remapping={"who": "guest"},
        )
    assert outer.execute() == "done"
    assert robot.calls == ["bob"]


def test_skill_machine_run_again_reports_only_what_it_saw_in_that_run() -> None:
    robot = Counter()
    sm = _greet(robot, {"who": "alice"})
    assert sm.execute() == "succeeded"
    sm.userdata.who = "nobody"
    assert sm.execute() == "aborted"
    assert sm.userdata.observations == {}


def test_skills_made_of_kit_parts_pass_the_registry_checks_and_feed_the_belief() -> None:
    task = rooms()
    world = SimulatedWorld(task)
    skills = symbolic_skills(world, SkillRegistry())

    class CheckDoor(RobotState[SimulatedWorld]):
        """The door from ``source`` to ``target`` is shut: report it, move nowhere."""

        def __init__(self, world: SimulatedWorld) -> None:
            super().__init__(world, ["shut"], input_keys=["source", "target"])

        def act(self, ud: smach.UserData) -> str:
            observe(ud, (fact("open", ud.source, ud.target), False))
            return "shut"

    @skills.register("move")
    def move(robot: str, source: str, target: str) -> smach.State:
        sm = skill_machine(bind={"robot": robot, "source": source, "target": target})
        with sm:
            smach.StateMachine.add("CHECK_DOOR", CheckDoor(world), {"shut": "aborted"})
        return sm

    assert skills.check(task) == []
    state, _ = skills.create(PlanStep("move", ("robot1", "hall", "office")))
    assert state.execute() == "aborted"
    assert normalise_observations(state.userdata.observations) == [
        (("open", "hall", "office"), False)
    ]
    executive = Executive(task, skills, get_planner("fast-downward"))
    assert executive.execute() == "aborted"  # no door is open, and the belief knows it
    assert ("open", "hall", "kitchen") not in executive.belief.facts
    assert world.holds("at", "robot1", "hall")


# -- routes ----------------------------------------------------------------------------------
#: a - b - d and a - c - d, plus a long corridor a - d; lengths in metres.
MAP = {("a", "b"): 1.0, ("b", "d"): 1.0, ("a", "c"): 1.0, ("c", "d"): 0.5, ("a", "d"): 5.0}


def _exits(place: str) -> list[tuple[str, float]]:
    out = [(b, m) for (a, b), m in MAP.items() if a == place]
    return out + [(a, m) for (a, b), m in MAP.items() if b == place]


def test_fewest_hops_takes_the_route_with_fewest_legs_and_names_what_each_goes_through() -> None:
    assert fewest_hops("a", "d", _exits) == [("a", "d", 5.0)]
    assert fewest_hops("b", "c", _exits) == [("b", "d", 1.0), ("d", "c", 0.5)]
    assert fewest_hops("a", "a", _exits) == []
    assert fewest_hops("a", "z", _exits) is None


def test_fewest_hops_breaks_ties_by_the_order_of_the_exits() -> None:
    def exits(place: str) -> list[tuple[str, None]]:
        return [(p, None) for p in {"a": ["c", "b"], "b": ["d"], "c": ["d"]}.get(place, [])]

    assert fewest_hops("a", "d", exits) == [("a", "c", None), ("c", "d", None)]


def test_shortest_route_minimises_the_total_length() -> None:
    assert shortest_route("a", "d", _exits) == ["a", "c", "d"]
    assert shortest_route("d", "b", _exits) == ["d", "b"]
    assert shortest_route("a", "a", _exits) == ["a"]
    assert shortest_route("a", "z", _exits) is None


def test_shortest_route_breaks_ties_the_same_way_whatever_the_order_of_the_exits() -> None:
    equal = {"s": [("y", 1.0), ("x", 1.0)], "x": [("t", 1.0)], "y": [("t", 1.0)]}
    assert shortest_route("s", "t", lambda p: equal.get(p, [])) == ["s", "x", "t"]
    assert shortest_route("s", "t", lambda p: reversed(equal.get(p, []))) == ["s", "x", "t"]
