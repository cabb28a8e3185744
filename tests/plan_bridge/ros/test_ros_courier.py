"""The example robot (domains/ros_courier) over real rclpy: its servers run in another
process (robot.py), the executive drives them through the ROS entries of its
skills.toml (tests/conftest.py keeps DDS on this machine, in a random domain)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from plan_bridge.execution.events import StepFinished
from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import load_target
from plan_bridge.skills.ros.skill_states import forget_servers
from smach.ros.dds import FAST_DDS_2_VARIABLE, FAST_DDS_3_VARIABLE

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[3]
COURIER = ROOT / "domains" / "ros_courier"
#: A seed of robot.py whose faults at --fail-rate 0.2 make p02's plan fail on the way.
FAULTY_SEED = 1


class Robot:
    """robot.py in its own process; every line it prints, with when it came."""

    def __init__(self, *options: str) -> None:
        env = {
            k: v
            for k, v in os.environ.items()
            if k not in (FAST_DDS_2_VARIABLE, FAST_DDS_3_VARIABLE)
        }
        self.process = subprocess.Popen(
            [sys.executable, str(COURIER / "robot.py"), *options],
            stdout=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            text=True,
            env=env,
        )
        self.lines: list[tuple[float, str]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        assert self.wait_for(lambda line: line == "ready", 60), self.text()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            self.lines.append((time.monotonic(), raw.rstrip("\n")))

    def wait_for(self, predicate: Callable[[str], bool], timeout: float) -> float | None:
        """When the first line that ``predicate`` accepts came (None: not within ``timeout``)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for when, line in list(self.lines):
                if predicate(line):
                    return when
            time.sleep(0.01)
        return None

    def text(self) -> str:
        return "\n".join(line for _, line in self.lines)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)
        self._reader.join(5)
        if self.process.stdout is not None:
            self.process.stdout.close()


@pytest.fixture
def robots() -> Iterator[list[Robot]]:
    started: list[Robot] = []
    try:
        yield started
    finally:
        for robot in started:
            robot.stop()
        forget_servers()


def start(robots: list[Robot], *options: str) -> Robot:
    robot = Robot(*options)
    robots.append(robot)
    return robot


def run_cli(*arguments: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "plan_bridge", *arguments],
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
        cwd=ROOT,
    )


@pytest.mark.timeout(180)
def test_the_courier_reaches_its_goal_over_ros_with_faults_injected_by_its_servers(
    robots: list[Robot], tmp_path: Path
) -> None:
    robot = start(robots, "--fail-rate", "0.2", "--seed", str(FAULTY_SEED))
    probed = run_cli("check", str(COURIER), "--problem", "p02", "--probe")
    assert probed.returncode == 0, probed.stderr
    assert probed.stderr.count(": up\n") == 4  # every declarative entry's server or topic
    journal = tmp_path / "run.jsonl"
    done = run_cli("run", str(COURIER), "--problem", "p02", "--json", "--journal", str(journal))
    assert done.returncode == 0, done.stderr + robot.text()
    report = json.loads(done.stdout)
    assert report["goal_reached"] and report["actions_failed"] >= 1
    # The servers injected them (their lines come through the reader thread).
    assert robot.wait_for(lambda line: "fault:" in line, 10) is not None, robot.text()
    # The journal holds what each step sent and received: goal, feedback, result.
    records = [json.loads(line) for line in journal.read_text().splitlines()]
    written = {
        (r["key"], r["writer"])
        for r in records
        if r.get("kind") == "userdata_written" and "_DRIVE_" in r["path"]
    }
    assert {("goal", "DRIVE"), ("feedback", "DRIVE"), ("result", "DRIVE")} <= written
    results = [
        r["value"] for r in records if r.get("kind") == "userdata_written" and r["key"] == "result"
    ]
    assert {"status": "succeeded", "result": {"sequence": [4]}} in results  # reached the office


def drive_started(robot: Robot) -> Callable[[], bool]:
    return lambda: robot.wait_for(lambda line: line.startswith("goal drive to"), 0) is not None


@pytest.mark.timeout(120)
def test_a_preempt_cancels_the_running_drive_goal_on_the_server(robots: list[Robot]) -> None:
    robot = start(robots, "--drive-time", "20")
    target = load_target(COURIER, "p01")
    setup = target.setup(seed=0, fail_rate=0.0)
    executive = Executive(target.task, setup.skills)
    box: dict[str, Any] = {}
    runner = threading.Thread(target=lambda: box.update(outcome=executive.execute()))
    runner.start()
    assert robot.wait_for(lambda line: line.startswith("goal drive to"), 60), robot.text()
    preempted = time.monotonic()
    executive.request_preempt()
    canceled = robot.wait_for(lambda line: line.startswith("canceled drive to"), 30)
    runner.join(30)
    returned = time.monotonic()
    assert canceled is not None, robot.text()
    assert box["outcome"] == "preempted"
    assert not any(line.startswith("succeeded drive") for _, line in robot.lines)
    print(
        f"\npreempt -> the server canceled the goal: {(canceled - preempted) * 1000:.0f} ms; "
        f"the executive returned: {(returned - preempted) * 1000:.0f} ms"
    )


@pytest.mark.timeout(120)
def test_killing_the_robot_mid_drive_aborts_the_step_within_its_lease_and_the_mission_ends(
    robots: list[Robot],
) -> None:
    robot = start(robots, "--drive-time", "30", "--lease", "2")
    target = load_target(COURIER, "p01")
    setup = target.setup(seed=0, fail_rate=0.0)
    executive = Executive(target.task, setup.skills)  # the default policy: 10 replans
    aborted: list[float] = []
    executive.add_listener(
        lambda e: (
            aborted.append(time.monotonic())
            if isinstance(e, StepFinished) and e.outcome == "aborted"
            else None
        )
    )
    box: dict[str, Any] = {}
    runner = threading.Thread(target=lambda: box.update(outcome=executive.execute()))
    runner.start()
    assert robot.wait_for(lambda line: line.startswith("goal drive to"), 60), robot.text()
    robot.process.kill()

    killed = time.monotonic()
    runner.join(90)
    ended = time.monotonic()
    assert not runner.is_alive() and box["outcome"] == "aborted"
    first_abort = aborted[0] - killed
    # The 2 s lease and two liveness checks 0.5 s apart, with room for a loaded machine;
    # Fast DDS's default lease alone would take 20 s.
    assert first_abort < 10.0
    assert "drive" in executive.report.explanation
    print(
        f"\nrobot SIGKILLed mid-drive -> step aborted after {first_abort:.1f} s, mission ended "
        f"after {ended - killed:.1f} s ({executive.report.explanation})"
    )


LEGACY_DRIVE = '''
"""A SimpleActionState kept from a SMACH program, bound by the skill map."""
import smach_ros
from test_msgs.action import Fibonacci

WAYPOINTS = {"mailroom": 1, "hall": 2, "lab": 3, "office": 4}


def drive_state(robot, origin, destination):
    return smach_ros.SimpleActionState(
        "/courier/drive", Fibonacci, goal=Fibonacci.Goal(order=WAYPOINTS[destination]),
        server_wait_timeout=10.0, exec_timeout=30.0,
    )
'''


@pytest.mark.timeout(120)
def test_a_map_entry_may_name_a_factory_that_returns_a_simple_action_state(
    robots: list[Robot], tmp_path: Path
) -> None:
    robot = start(robots)
    folder = tmp_path / "ported"
    shutil.copytree(COURIER, folder, ignore=shutil.ignore_patterns("__pycache__"))
    (folder / "legacy_drive.py").write_text(LEGACY_DRIVE, encoding="utf-8")
    text = (folder / "skills.toml").read_text(encoding="utf-8")
    start_at, end_at = text.index("[drive]"), text.index("[pick-up]")
    ported = '[drive]\nfactory = "legacy_drive:drive_state"\n\n'
    (folder / "skills.toml").write_text(text[:start_at] + ported + text[end_at:], encoding="utf-8")
    target = load_target(folder, "p01")
    setup = target.setup(seed=0, fail_rate=0.0)
    executive = Executive(target.task, setup.skills)
    assert executive.execute() == "succeeded", robot.text()
    assert robot.wait_for(lambda line: line == "succeeded drive to lab", 5) is not None
