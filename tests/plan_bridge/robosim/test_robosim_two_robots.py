"""domains/robosim_two_robots: two robots on one pyrobosim world and one simulated clock,
planned (Kairos, both robots' steps dispatched at once) and scripted (one machine per
robot in a TurnTakingConcurrence)."""

from __future__ import annotations

import threading
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

import smach
from plan_bridge.cli import main
from plan_bridge.missions.mission import ScriptedMission, load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.robosim.world import RobosimWorld

TWO = Path(__file__).resolve().parents[3] / "domains" / "robosim_two_robots"
CLOSE = TWO / "events" / "close_hallway.yaml"

Span = tuple[str, str, float, float]  # (robot, action, simulated start, simulated end)


def planned(problem: str | None = None, **options: Any) -> tuple[Any, RobosimWorld, list[Span]]:
    """Run the planned mission; its figures, its world and every step's simulated span."""
    events = options.pop("events", None)
    mission = prepare_mission(load_target(TWO, problem, events=events), MissionOptions(**options))
    world = mission.world
    assert isinstance(world, RobosimWorld)
    started: dict[str, float] = {}
    spans: list[Span] = []

    def listen(event: Any) -> None:  # (told in the step's own thread, on its turn)
        if event.kind == "action_started":
            started[event.path] = world.now()
        elif event.kind == "action_ended" and event.outcome == "succeeded":
            spans.append((event.action.split()[1], event.action, started[event.path], world.now()))

    mission.executive.add_listener(listen)
    mission.run()
    return {**mission.figures(), "executed": mission.executive.report.executed}, world, spans


def busy(spans: list[Span]) -> dict[str, float]:
    """Simulated seconds each robot spent in its steps."""
    total: dict[str, float] = defaultdict(float)
    for robot, _, start, end in spans:
        total[robot] += end - start
    return dict(total)


def overlap(spans: list[Span], a: str, b: str) -> float:
    """Simulated seconds during which robots ``a`` and ``b`` both ran a step."""
    return sum(
        max(0.0, min(e1, e2) - max(s1, s2))
        for r1, _, s1, e1 in spans
        for r2, _, s2, e2 in spans
        if (r1, r2) == (a, b)
    )


def test_the_planned_mission_runs_both_robots_steps_at_once() -> None:
    figures, world, spans = planned(fail_rate=0.0)
    assert figures["goal_reached"] and world.goal_reached()
    work = busy(spans)
    assert set(work) == {"ada", "bob"}
    # Both robots drive at the same time: the makespan is the slower robot's work, not
    # the sum of the two (measured: 49.0 s against 30.2 + 49.0 s).
    assert overlap(spans, "ada", "bob") > 20.0
    assert world.now() == pytest.approx(max(work.values()), abs=0.1)
    assert world.now() < 0.75 * sum(work.values())


def test_the_planned_hand_over_opens_the_locker_before_the_bolt_box_arrives() -> None:
    figures, _, spans = planned("hand_over", fail_rate=0.0)
    assert figures["goal_reached"]
    (opened,) = [s for s in spans if s[1].startswith("(open bob locker")]
    (placed,) = [s for s in spans if s[1].startswith("(place ada bolt_box")]
    # bob (next to it, hand empty) opens the locker while ada carries the box over.
    assert opened[3] <= placed[2]
    assert overlap(spans, "ada", "bob") > 0.0


def test_the_planned_mission_replans_around_the_hallway_closed_on_the_carriers_way() -> None:
    figures, world, spans = planned(seed=0, fail_rate=0.0, events=CLOSE)
    assert figures["goal_reached"] and figures["replans"] >= 1
    assert [c.split(": ")[1] for c in world.changes] == [
        "hall_lab_workshop closed",
        "hall_lab_workshop locked",
    ]
    # The robot carrying the wrench to the lab found the hallway shut and went round
    # through the store.
    (carrier,) = {
        robot
        for robot, action, _, _ in spans
        if action.startswith("(place ") and " wrench " in action
    }
    assert world.crossed[carrier][-2:] == ["hall_store_workshop", "hall_lab_store"]
    assert "hall_lab_workshop" not in world.crossed[carrier]


def scripted(problem: str | None = None, **options: Any) -> ScriptedMission:
    target = load_target(TWO, problem)
    assert target.module is not None, "the world folder's Python is loaded"
    mission: ScriptedMission = target.module.scripted(target.task, **options)
    return mission


def run_scripted(mission: ScriptedMission) -> tuple[str, smach.UserData, dict[str, float]]:
    """Execute the baseline: its outcome, its userdata and the simulated seconds each
    thread (each robot's machine runs in one) spent in actions."""
    world = mission.world
    assert isinstance(world, RobosimWorld)
    spent: dict[str, float] = defaultdict(float)
    elapse = world.elapse

    def counted(seconds: float) -> None:
        spent[threading.current_thread().name] += max(0.0, seconds)
        elapse(seconds)

    world.elapse = counted  # type: ignore[method-assign]
    machine = mission.machine
    assert isinstance(machine, smach.Concurrence)
    return str(machine.execute()), machine.userdata, dict(spent)


def test_the_scripted_robots_work_at_once_and_a_seeded_run_repeats() -> None:
    ends = []
    for _ in range(2):
        mission = scripted(seed=3, fail_rate=0.2)
        outcome, ud, spent = run_scripted(mission)
        world = mission.world
        assert isinstance(world, RobosimWorld)
        assert outcome == "succeeded" and world.goal_reached()
        assert ud.ada_legs and ud.bob_legs
        # Two threads took turns on the clock: its time is the longer robot's, not the sum.
        assert len(spent) == 2
        assert world.now() == pytest.approx(max(spent.values()), abs=1e-6)
        assert world.now() < 0.75 * sum(spent.values())
        ends.append((ud.ada_legs, ud.bob_legs, world.figures(), world.changes))
    assert ends[0] == ends[1] and ends[0][2]["faults_injected"] > 0


def test_the_scripted_robots_go_round_a_closed_hallway_and_hand_over() -> None:
    mission = scripted(seed=0, fail_rate=0.0, variant="close_hallway")
    outcome, ud, _ = run_scripted(mission)
    assert outcome == "succeeded" and mission.world.goal_reached()
    assert ud.blocked == ["hall_lab_workshop"]
    crossed = [leg.split()[-1] for leg in ud.ada_legs if leg.startswith("cross")]
    assert crossed[-2:] == ["hall_store_workshop", "hall_lab_store"]  # round by the store
    hand_over = scripted("hand_over", seed=0, fail_rate=0.0)
    jobs = hand_over.extra["jobs"]
    assert jobs["bob"].opens == ["locker_shelf"] and not jobs["bob"].deliveries
    outcome, ud, _ = run_scripted(hand_over)
    assert outcome == "succeeded" and hand_over.world.goal_reached()
    assert ud.bob_legs == ["navigate lab locker_shelf"]


def test_the_impossible_variant_ends_with_exit_1_and_a_reason(
    capsys: pytest.CaptureFixture[str],
) -> None:
    events = str(TWO / "events" / "lock_all.yaml")
    args = ["run", str(TWO), "--events", events, "--fail-rate", "0", "--planner", "kairos"]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "goal NOT reached" in err and "no plan" in err
    outcome, _, _ = run_scripted(scripted(seed=0, fail_rate=0.0, variant="lock_all"))
    assert outcome == "aborted"


def test_the_skills_of_the_world_folder_are_the_robosim_ones(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["skills", str(TWO)]) == 0
    assert "9 domain skills" in capsys.readouterr().out
