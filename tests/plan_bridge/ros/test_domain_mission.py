"""The fetch_drink mission across processes: the executive here, the robot node there.

The robot node (``python -m plan_bridge.ros.skill_server domains/fetch_drink``) runs
the domain's own skill state machines against its simulated world (world.py, with
its faults); the executive drives them over ROS 2 (tests/conftest.py keeps DDS on
this machine, in a random domain).
"""

from __future__ import annotations

import json
import os
import signal
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

from plan_bridge.execution.events import StepFinished
from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import Target, load_target
from plan_bridge.planning.planner import get_planner
from plan_bridge.ros import remote_facts
from plan_bridge.ros.connection import RobotConnection, RobotError
from smach.introspection.journal import read_states
from smach.ros.dds import FAST_DDS_2_VARIABLE, FAST_DDS_3_VARIABLE

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[3]
FETCH = ROOT / "domains" / "fetch_drink"
#: Seed and fault rate where faults make the first plan fail (a blocked corridor
#: and a misplaced drink at p01), so the executive must replan to reach the goal.
FAULTY_SEED, FAULTY_RATE = 1, 0.2


@pytest.fixture(scope="module")
def planner() -> Any:
    return get_planner("fast-downward")


@pytest.fixture
def target() -> Target:
    return load_target(FETCH, "p01")


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


@pytest.mark.timeout(120)
def test_fetch_drink_succeeds_across_processes_without_faults(
    robots: list[RobotConnection], target: Target, planner: Any
) -> None:
    robot = start(robots, target, fail_rate=0.0, time_scale=0.0)
    assert robot.robot_info["mode"] == "domain skills"
    assert robot.robot_info["faults_injected"] == 0
    started = time.monotonic()
    ex = Executive(target.task, robot.skills(), planner)
    assert ex.execute() == "succeeded"
    elapsed = time.monotonic() - started
    assert ex.report.goal_reached and ex.report.actions_failed == 0
    # The robot's own world (not just the executive's belief) reached the goal.
    info = robot.info()
    assert info is not None and info["goal_reached"] and info["busy"] == []
    facts = remote_facts(robot.node, prefix=robot.prefix)
    assert "(served alice cola)" in facts and "(fridge-closed kitchen-fridge)" in facts
    # The skill machines ran in the robot process: it printed their states (the last
    # line maybe after its result reached the executive).
    assert wait_until(lambda: "succeeded (hand-over pr2 cola alice living-room)" in robot.lines)
    assert "  state /pick-drink/GRASP/ATTEMPT/CLOSE_GRIPPER" in robot.lines
    print(
        f"\ncross-process mission: {elapsed:.2f} s ({ex.report.execution_time_s:.2f} s executing)"
    )


@pytest.mark.timeout(120)
def test_faults_on_the_robot_trigger_replanning_and_the_goal_is_still_reached(
    robots: list[RobotConnection], target: Target, planner: Any
) -> None:
    robot = start(robots, target, seed=FAULTY_SEED, fail_rate=FAULTY_RATE, time_scale=0.0)
    ex = Executive(target.task, robot.skills(), planner)
    assert ex.execute() == "succeeded"
    assert ex.report.actions_failed >= 1
    assert ex.report.replans >= 1
    info = robot.info()
    assert info is not None and info["goal_reached"] and info["faults_injected"] >= 1
    # What the robot's skills observed reached the executive's belief: where the
    # misplaced drink really was (the robot's DETECT state saw it).
    reasons = " ".join(d["reason"] for d in ex.report.decisions)
    assert "(on cola bottom-shelf)" in reasons
    assert wait_until(lambda: any(line.startswith("failed (pick-drink") for line in robot.lines))


@pytest.mark.timeout(120)
def test_preempting_the_executive_cancels_the_remote_skill_and_stops_the_robot(
    robots: list[RobotConnection], target: Target, planner: Any
) -> None:
    # Slow robot: a corridor (3 to 8 m at 0.6 m/s) takes 2.5 to 7 s of wall time.
    robot = start(robots, target, fail_rate=0.0, time_scale=0.5)
    ex = Executive(target.task, robot.skills(), planner)
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=ex.execute()))
    thread.start()
    try:
        driving = "  state /navigate/DRIVE/ATTEMPT/DRIVE"
        assert wait_until(lambda: driving in robot.lines, 60)
        time.sleep(0.3)
        asked = time.monotonic()
        ex.request_preempt()
        assert wait_until(lambda: any(x.startswith("canceled (navigate") for x in robot.lines), 10)
        cancelled = time.monotonic() - asked
        thread.join(10)
        returned = time.monotonic() - asked
    finally:
        ex.request_preempt()
        thread.join(30)
    assert box["outcome"] == "preempted"
    assert cancelled < 2.0 and returned < 3.0
    # The robot stopped: the drive was cut short, so the robot is still where it
    # started, and no skill runs any more.
    info = robot.info()
    assert info is not None and info["busy"] == [] and not info["goal_reached"]
    facts = remote_facts(robot.node, prefix=robot.prefix)
    assert "(at pr2 living-room)" in facts
    assert not any(line.startswith("succeeded (navigate") for line in robot.lines)
    print(
        f"\npreempt -> robot canceled: {cancelled * 1000:.0f} ms; executive returned: "
        f"{returned * 1000:.0f} ms"
    )


@pytest.mark.timeout(60)
def test_the_robot_process_is_stopped_when_the_connection_closes(
    robots: list[RobotConnection], target: Target
) -> None:
    robot = start(robots, target, fail_rate=0.0)
    process = robot.process
    assert process is not None and process.poll() is None
    robot.close()
    assert process.poll() is not None
    assert "faults 0" in robot.lines  # it shut down cleanly (SIGTERM), not killed


@pytest.mark.timeout(60)
def test_a_robot_running_another_problem_is_refused(
    robots: list[RobotConnection], target: Target
) -> None:
    other = start(robots, load_target(FETCH, "p02"), fail_rate=0.0, prefix="robot_p02")
    with pytest.raises(RobotError, match=r"not fetch_drink p01\.pddl"):
        start(robots, target, start_robot=False, prefix=other.prefix, wait_timeout=10)


@pytest.mark.timeout(120)
@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_a_robot_killed_mid_skill_ends_the_mission_within_a_bounded_time(
    robots: list[RobotConnection], target: Target, planner: Any, how: signal.Signals
) -> None:
    robot = start(robots, target, fail_rate=0.0, time_scale=0.5)
    ex = Executive(target.task, robot.skills(), planner)
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=ex.execute()))
    thread.start()
    assert wait_until(lambda: "  state /navigate/DRIVE/ATTEMPT/DRIVE" in robot.lines, 60)
    assert robot.process is not None
    killed = time.monotonic()
    aborted: list[float] = []
    ex.add_listener(
        lambda e: (
            aborted.append(time.monotonic())
            if isinstance(e, StepFinished) and e.outcome == "aborted"
            else None
        )
    )
    robot.process.send_signal(how)
    thread.join(90)
    first_abort = aborted[0] - killed
    assert first_abort < 6.0 and time.monotonic() - killed < 30.0
    ended = time.monotonic() - killed
    assert not thread.is_alive()
    assert box["outcome"] == "aborted"
    assert ex.report.actions_failed >= 1
    print(
        f"\nrobot {how.name} -> mission aborted after {ended:.1f} s ({ex.report.planner_calls} "
        f"planner calls, {ex.report.planning_time_s:.1f} s planning; first step aborted after "
        f"{first_abort:.1f} s)"
    )


@pytest.mark.timeout(120)
def test_a_robot_with_the_default_lease_killed_mid_skill_is_caught_by_its_heartbeat(
    robots: list[RobotConnection], target: Target, planner: Any
) -> None:
    # A robot started by someone else, with Fast DDS's default 20 s lease (--lease 0,
    # no profile): only the heartbeat can tell within seconds that it died.
    prefix = f"robot_beat_{os.getpid()}"
    env = {
        k: v for k, v in os.environ.items() if k not in (FAST_DDS_2_VARIABLE, FAST_DDS_3_VARIABLE)
    }
    command = [sys.executable, "-m", "plan_bridge.ros.skill_server", str(FETCH),
               "--problem", str(target.problem_path), "--prefix", prefix, "--fail-rate", "0",
               "--time-scale", "0.5", "--lease", "0"]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=env)
    lines: list[str] = []

    def pump() -> None:
        assert process.stdout is not None
        lines.extend(line.rstrip("\n") for line in process.stdout)

    pumping = threading.Thread(target=pump, daemon=True)
    pumping.start()
    try:
        assert wait_until(lambda: "ready" in lines, 60)
        robot = start(robots, target, start_robot=False, prefix=prefix)
        ex = Executive(target.task, robot.skills(), planner)
        aborted: list[float] = []
        ex.add_listener(
            lambda e: (
                aborted.append(time.monotonic())
                if isinstance(e, StepFinished) and e.outcome == "aborted"
                else None
            )
        )
        box: dict[str, Any] = {}
        thread = threading.Thread(target=lambda: box.update(outcome=ex.execute()))
        thread.start()
        assert wait_until(lambda: "  state /navigate/DRIVE/ATTEMPT/DRIVE" in lines, 60)
        process.kill()
        killed = time.monotonic()
        thread.join(90)
        assert not thread.is_alive() and box["outcome"] == "aborted"
        first_abort = aborted[0] - killed
        # HEARTBEAT_TIMEOUT (3 s) + two liveness checks (1 s), with room for a loaded
        # machine; the robot's DDS lease alone would take 20 s.
        assert first_abort < 10.0
        reason = robot.lost()
        assert reason is not None and "heartbeat" in reason
        print(
            f"\nrobot with a 20 s lease SIGKILLed -> first step aborted after {first_abort:.1f} s"
        )
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(10)
        pumping.join(10)  # the pipe's end reached: now it can be closed
        assert process.stdout is not None
        process.stdout.close()


@pytest.mark.timeout(120)
def test_plan_bridge_run_ros_json_exits_0(tmp_path: Path) -> None:
    started = time.monotonic()
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "plan_bridge",
            "run",
            str(FETCH),
            "--ros",
            "--json",
            "--seed",
            str(FAULTY_SEED),
            "--fail-rate",
            str(FAULTY_RATE),
            "--journal",
            str(tmp_path / "run.jsonl"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=dict(os.environ),
        timeout=100,
    )
    elapsed = time.monotonic() - started
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["goal_reached"] and data["replans"] >= 1
    assert data["ros"]["robot"] == "started"
    assert data["ros"]["robot_info"]["goal_reached"]
    assert data["faults_injected"] >= 1
    assert "ros: robot node" in result.stderr and "(started here, pid" in result.stderr
    # One line per step, as without --ros; the robot's own lines only with -v.
    assert "step 1: (navigate" in result.stderr and "[robot]" not in result.stderr
    # The robot process it started is gone.
    pid = data["ros"]["robot_info"]["pid"]
    assert wait_until(lambda: not Path(f"/proc/{pid}").exists(), 5)
    # Journal checkpoints of a --ros run hold no world snapshot (it is on the robot).
    records = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    checkpoints = read_states(records, "checkpoint")
    assert checkpoints and all("world" in r and r["world"] is None for r in checkpoints)
    print(f"\nplan-bridge run --ros --json: {elapsed:.2f} s")


@pytest.mark.timeout(120)
def test_plan_bridge_run_ros_verbose_adds_the_robot_lines() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "plan_bridge", "run", str(FETCH), "--ros", "-v",
         "--fail-rate", "0"],
        capture_output=True, text=True, cwd=ROOT, env=dict(os.environ), timeout=100,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    lines = result.stderr.splitlines()
    goal = lines.index("  [robot] goal (navigate pr2 living-room dining-room)")
    step = next(i for i, line in enumerate(lines) if line.startswith("  step 1: (navigate"))
    assert goal < step  # the robot's lines come between the executive's steps
    assert any(line.startswith("  [robot]   state /navigate/") for line in lines[goal:step])
