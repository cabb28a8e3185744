"""`plan-bridge skills` and `check` with the ROS entries of a skill map, no robot running:
every mistake at its FILE:LINE (exit 2), --probe naming what is not up (exit 1), a
warning for a skill without a preempted outcome."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from plan_bridge.cli import main

ROOT = Path(__file__).resolve().parents[3]
COURIER = ROOT / "domains" / "ros_courier"


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A copy of the example robot's folder (PDDL, tables, skills.toml)."""
    target = tmp_path / "ros_courier"
    shutil.copytree(COURIER, target, ignore=shutil.ignore_patterns("__pycache__"))
    return target


def test_skills_lists_the_action_service_or_topic_each_action_runs_on(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["skills", str(COURIER), "--json"]) == 0
    rows = {row["action"]: row for row in json.loads(capsys.readouterr().out)["actions"]}
    assert rows["drive"]["ros"] == {
        "kind": "action",
        "name": "/courier/drive",
        "type": "test_msgs/action/Fibonacci",
    }
    assert rows["drive"]["outcome_map"] == {"off-route": "aborted"}
    assert rows["confirm-delivery"]["ros"]["kind"] == "topic"
    assert "ros" not in rows["drop"] and rows["drop"]["factory"] == "legacy_states:open_gripper"


def test_check_reports_each_mistake_of_the_ros_entries_at_its_line_and_exits_2(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = folder / "skills.toml"
    text = path.read_text(encoding="utf-8")
    text = text.replace(
        '"initial_pose.pose.pose" = "poses.yaml:?p"', '"initial_pose.pose.pos" = "poses.yaml:?p"'
    )
    text = text.replace('type = "std_srvs/srv/SetBool"', 'type = "std_srvs/srv/SetBoolean"')
    (folder / "waypoints.yaml").write_text("mailroom: 1\nhall: 2\nlab: 3\n", encoding="utf-8")
    path.write_text(text, encoding="utf-8")
    assert main(["check", str(folder), "--problem", "p01"]) == 2
    err = capsys.readouterr().err
    assert (
        f"{path}:12: [localize]: request \"initial_pose.pose.pos\": geometry_msgs/msg/PoseWithCovariance has no field 'pos' (did you mean pose?)"
        in err
    )
    assert (
        f'{path}:17: [drive]: goal "order": waypoints.yaml has no entry for office (the objects of type place (?to)); its keys: hall, lab, mailroom'
        in err
    )
    assert (
        f"{path}:26: [pick-up]: type std_srvs/srv/SetBoolean: std_srvs/srv has no 'SetBoolean' (did you mean SetBool?); its srv types: Empty, SetBool, Trigger"
        in err
    )
    assert "Traceback" not in err


def test_check_warns_about_a_skill_without_preempted(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (folder / "legacy_states.py").write_text(
        "import smach\n\n\nclass Drop(smach.State):\n"
        "    def __init__(self, robot, parcel, place):\n"
        "        super().__init__(outcomes=['succeeded', 'aborted'])\n\n"
        "    def execute(self, ud):\n        return 'succeeded'\n\n\n"
        "def open_gripper(robot, parcel, place):\n    return Drop(robot, parcel, place)\n",
        encoding="utf-8",
    )
    assert main(["check", str(folder), "--problem", "p01"]) == 0
    err = capsys.readouterr().err
    assert (
        "warning: p01.pddl: skill 'drop': it has no outcome 'preempted' (outcomes: succeeded, "
        "aborted): a preempt does not stop it; the executive lets such a step finish before it "
        "stops the plan"
    ) in err


def test_check_probe_names_each_server_that_is_not_up_and_exits_1(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    skills = folder / "skills.toml"
    # Servers nobody runs (another prefix than the example robot's, were one running).
    skills.write_text(
        skills.read_text(encoding="utf-8").replace("/courier/", "/nobody_here/"), encoding="utf-8"
    )
    assert main(["check", str(folder), "--problem", "p01", "--probe", "0.2"]) == 1
    err = capsys.readouterr().err
    assert (
        f"probe: {skills}:14: [drive]: ROS action /nobody_here/drive (test_msgs/action/Fibonacci): not up"
        in err
    )
    assert "4 ROS server(s) of the skill map not ready" in err


def test_the_readmes_nav2_map_is_only_refused_for_the_missing_nav2_msgs(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    readme = (COURIER / "README.md").read_text(encoding="utf-8")
    nav2 = readme.split("```toml\n", 1)[1].split("```", 1)[0]
    skills = folder / "skills.toml"
    text = skills.read_text(encoding="utf-8")
    start_at, end_at = text.index("[drive]"), text.index("[pick-up]")
    skills.write_text(text[:start_at] + nav2 + "\n" + text[end_at:], encoding="utf-8")
    assert main(["check", str(folder), "--problem", "p01"]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith(f"plan-bridge: error: {skills}:")
        and "[drive]: type nav2_msgs/action/NavigateToPose: the message package nav2_msgs is not installed; install it: pip install ros-jazzy-nav2-msgs"
        in err
    )
    assert err.count(f"{skills}:") == 1  # nothing else of the entry is refused
