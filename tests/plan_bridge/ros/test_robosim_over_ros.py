"""A pyrobosim world on a robot node: the robosim skills as ROS 2 actions over real rclpy.

The robot node (``python -m plan_bridge.ros.skill_server domains/robosim_fetch``) loads
the pyrobosim world and runs the robosim skill machines against it in its own process;
the executive drives them over ROS 2 (tests/conftest.py keeps DDS on this machine, in a
random domain).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from waiting import wait_until

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

import smach
from plan_bridge.missions.mission import Target, load_target
from plan_bridge.planning.planner import PlanStep
from plan_bridge.ros import decode_result, encode_result, remote_facts, ros_skill
from plan_bridge.ros.connection import RobotConnection, RobotError

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[3]
FETCH = ROOT / "domains" / "robosim_fetch"
CLOSE_HALLWAY = FETCH / "events" / "close_hallway.yaml"
#: Runs block on Python starting twice, pyrobosim and the planner: seconds, not minutes.
RUN_TIMEOUT = 100
#: Imports nothing of pyrobosim (as if it were not installed), then runs ``code``.
WITHOUT_PYROBOSIM = "import sys, runpy; sys.modules['pyrobosim'] = None; "


def plan_bridge(*args: str, timeout: float = RUN_TIMEOUT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "plan_bridge", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=dict(os.environ),
        timeout=timeout,
    )


def python(code: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=dict(os.environ),
        timeout=timeout,
    )


@pytest.fixture
def robots() -> Iterator[list[RobotConnection]]:
    """Connections opened by a test; each is closed (its robot process stopped)."""
    opened: list[RobotConnection] = []
    try:
        yield opened
    finally:
        for robot in opened:
            robot.close()


def start(robots: list[RobotConnection], target: Target, **options: Any) -> RobotConnection:
    robot = RobotConnection(target, **options)
    robots.append(robot)
    return robot.open()


def test_numeric_readings_cross_the_wire_and_integers_are_refused() -> None:
    text = encode_result(True, [(("battery-level", "robot"), 20.905), (("at", "robot", "x"), True)])
    assert decode_result(text)[1] == [
        (("battery-level", "robot"), 20.905),
        (("at", "robot", "x"), True),
    ]
    for bad in ('[["(x)", 1]]', '[["(x)", NaN]]', '[["(x)", Infinity]]', '[["(x)", "1.0"]]'):
        with pytest.raises(ValueError, match="numeric fluent"):
            decode_result(f'{{"outcome": "succeeded", "observations": {bad}}}')


@pytest.mark.timeout(120)
def test_a_robosim_robot_node_serves_its_skills_and_a_cancel_stops_pyrobosims_drive(
    robots: list[RobotConnection],
) -> None:
    target = load_target(FETCH)  # fetch_soda, the folder's first goal
    # Real time: the 3.3 s drive to the charger takes 3.3 s of wall time.
    robot = start(robots, target, fail_rate=0.0, time_scale=1.0)
    info = robot.robot_info
    assert info["mode"] == "pyrobosim skills" and info["goal_name"] == "fetch_soda"
    assert info["figures"]["distance_m"] == 0.0 and info["figures"]["battery"] == {"robot": 25.0}
    facts = remote_facts(robot.node, prefix=robot.prefix)
    assert "(at robot living_room)" in facts and "(handempty robot)" in facts
    assert "(at soda fridge_shelf)" in facts and "(is-charger charger)" in facts
    assert "(isopen fridge)" not in facts

    state = ros_skill(
        robot.node, PlanStep("navigate", ("robot", "living_room", "charger_dock")),
        prefix=robot.prefix,
    )  # fmt: skip
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=state.execute(smach.UserData())))
    thread.start()
    try:
        assert wait_until(lambda: "  state /navigate/DRIVE" in robot.lines, 30)
        time.sleep(0.8)
        asked = time.monotonic()
        state.request_preempt()
        thread.join(10)
        returned = time.monotonic() - asked
    finally:
        state.request_preempt()
        thread.join(10)
    assert box["outcome"] == "preempted" and returned < 2.0
    # The robot prints the line when its process gets to it, maybe after the preempt returned.
    canceled = "canceled (navigate robot living_room charger_dock)"
    assert wait_until(lambda: canceled in robot.lines), list(robot.lines)
    # pyrobosim's drive stopped where the robot was: part of the way, not at the dock.
    now = robot.info()
    assert now is not None and now["busy"] == [] and now["actions_run"] == 1
    assert 0.3 < now["figures"]["distance_m"] < 2.5, now["figures"]
    assert "(at robot charger_dock)" not in remote_facts(robot.node, prefix=robot.prefix)

    # An executive with another goal of the same world is refused (another problem).
    other = load_target(FETCH, "apple_to_table")
    with pytest.raises(RobotError, match="not robosim_fetch"):
        start(robots, other, start_robot=False, prefix=robot.prefix, wait_timeout=10)
    # Stopped (SIGTERM), the robot node exits by itself: no pyrobosim thread holds it.
    process = robot.process
    assert process is not None
    robot.close()
    assert process.returncode == 0 and "faults 0" in robot.lines
    print(f"\npreempt -> skill preempted: {returned * 1000:.0f} ms")


@pytest.mark.timeout(240)
def test_plan_bridge_run_ros_reaches_the_goal_as_in_one_process_events_on_the_robot() -> None:
    options = ["--seed", "1", "--fail-rate", "0.2", "--events", str(CLOSE_HALLWAY), "--json"]
    started = time.monotonic()
    across = plan_bridge("run", str(FETCH), "--ros", "-v", *options)
    elapsed = time.monotonic() - started
    assert across.returncode == 0, across.stderr
    local = plan_bridge("run", str(FETCH), *options)
    assert local.returncode == 0, local.stderr
    ros, alone = json.loads(across.stdout), json.loads(local.stdout)
    assert ros["goal_reached"] and ros["ros"]["robot"] == "started"
    # The world runs in a world node, the robot's skills in a node of their own.
    assert "ros: robot node of robot " in across.stderr
    assert "  [robot]   state /navigate/DRIVE" in across.stderr
    # The events happened in the world node, which the executive learnt of through
    # the skills' observations: it replanned through the office.
    # (At 22 s, or once the robot left the hallway: pyrobosim closes none with a robot in it.)
    assert re.search(
        r"  \[world\] world 22\.\d\d s: hall_kitchen_living_room closed", across.stderr
    )
    assert ros["world_changes"] == 2 and ros["replans"] >= 1
    # The same run as in one process: steps, faults, distance and battery (the
    # robot's figures come over its info service).
    for key in ("executed", "faults_injected", "distance_m", "battery", "battery_used"):
        assert ros[key] == alone[key], key
    assert ros["ros"]["robot_info"]["events"] == str(CLOSE_HALLWAY)
    print(f"\nplan-bridge run robosim_fetch --ros: {elapsed:.2f} s")


@pytest.mark.timeout(120)
def test_a_world_file_with_a_goal_runs_across_processes() -> None:
    from pyrobosim.utils.general import get_data_folder

    world = Path(get_data_folder()) / "test_world.yaml"
    result = plan_bridge(
        "run", str(world), "--goal", "(At apple0 table0_tabletop)", "--ros", "--json",
        "--fail-rate", "0",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["goal_reached"] and data["faults_injected"] == 0 and data["distance_m"] > 0
    assert "pyrobosim skills on the robot node" in result.stderr
    assert "goal (At apple0 table0_tabletop)" in result.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--goal", "(At soda nowhere)"], "'nowhere' is not a robot, room"),
        (["--no-robot", "--events", str(CLOSE_HALLWAY)], "give them to the robot node"),
        (["--snapshot", "run.svg"], "--snapshot cannot be combined with --ros"),
    ],
    ids=["bad-goal", "events-without-robot", "snapshot"],
)
def test_run_ros_refuses_in_one_line_before_starting_a_robot(args: list[str], message: str) -> None:
    result = plan_bridge("run", str(FETCH), "--ros", *args, timeout=50)
    assert result.returncode == 2
    assert message in result.stderr and "Traceback" not in result.stderr
    assert "ros: starting" not in result.stderr


@pytest.mark.timeout(60)
def test_without_pyrobosim_both_sides_say_how_to_install_it() -> None:
    executive = python(
        WITHOUT_PYROBOSIM + "sys.argv = ['plan-bridge', 'run', 'domains/robosim_fetch', '--ros']; "
        "runpy.run_module('plan_bridge', run_name='__main__')"
    )
    robot = python(
        WITHOUT_PYROBOSIM + "from plan_bridge.ros.skill_server import main; "
        "sys.exit(main(['domains/robosim_fetch']))"
    )
    for result in (executive, robot):
        assert result.returncode == 2, result.stderr
        assert "pyrobosim is not installed" in result.stderr and "[sim]" in result.stderr
        assert "Traceback" not in result.stderr


@pytest.mark.timeout(60)
def test_a_robot_node_with_a_bad_goal_or_events_exits_2_with_the_reason(tmp_path: Path) -> None:
    bad_goal = python(
        "import sys; from plan_bridge.ros.skill_server import main; "
        "sys.exit(main(['domains/robosim_fetch', '--goal', '(At soda fridge_shelff)']))"
    )
    events = tmp_path / "events.yaml"
    events.write_text("- at: 3\n  close: nowhere_hall\n")
    bad_events = python(
        "import sys; from plan_bridge.ros.skill_server import main; "
        f"sys.exit(main(['domains/robosim_fetch', '--events', {str(events)!r}]))"
    )
    for result, reason in ((bad_goal, "fridge_shelf"), (bad_events, "nowhere_hall")):
        assert result.returncode == 2, result.stderr
        assert result.stderr.startswith("skill_server: ") and reason in result.stderr
        assert "Traceback" not in result.stderr
