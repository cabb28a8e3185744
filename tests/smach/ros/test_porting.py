"""Porting ROS 1-era SMACH programs: only the lines the port checker flags change.

``porting/ros1/`` holds programs written as for ROS 1 (rospy, actionlib message
spellings, states without a node); ``porting/ported/`` the same programs after the
port. Each ported program must differ from its original only in lines that
``smach.port_check`` reports as needing a change, and must run over real rclpy
against the test servers. ``porting/ros2/`` holds a program in the ROS 2
smach_ros style (node first), run unchanged.
"""

from __future__ import annotations

import difflib
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from smach.port_check import CHANGE, check_file

PORTING = Path(__file__).parent / "porting"
ROS1 = PORTING / "ros1"
PORTED = PORTING / "ported"
SRC = Path(__file__).parents[3] / "src"

#: fixture -> (servers to start, the line the program prints)
PROGRAMS: dict[str, tuple[list[list[str]], str]] = {
    "core_only": ([], "outcome: ok n: 4"),
    "state_machine": ([], "outcome: finished laps: 3"),
    "concurrence": ([], "outcome: greeted room: kitchen"),
    "iterator": ([], "outcome: toured visited: hall,lab,dock"),
    "condition_state": ([], "outcome: ready polls: 3"),
    "service_state": ([["setbool", "port_setbool"]], "outcome: off reply: got True"),
    "simple_action_state": (
        [["fibonacci", "port_fibonacci", "--step", "0.01"]],
        "outcome: done first: [0, 1, 1] last: 5",
    ),
    "monitor_state": (
        [["publish", "/port_chatter", "--rate", "50"]],
        "outcome: calm seen: 3",
    ),
    "action_server_wrapper": ([], "outcome: done answer: [0, 1, 1, 2, 3, 5]"),
}


def run_program(path: Path, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(path)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=dict(os.environ, PYTHONPATH=str(SRC)),
        check=False,
    )


def test_every_ros1_program_has_a_ported_version() -> None:
    assert sorted(p.name for p in ROS1.glob("*.py")) == sorted(p.name for p in PORTED.glob("*.py"))
    assert sorted(p.stem for p in ROS1.glob("*.py")) == sorted(PROGRAMS)


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_port_changes_only_lines_the_checker_flags(name: str) -> None:
    original = (ROS1 / f"{name}.py").read_text().splitlines()
    ported = (PORTED / f"{name}.py").read_text().splitlines()
    flagged = {f.line for f in check_file(ROS1 / f"{name}.py") if f.kind == CHANGE}
    matcher = difflib.SequenceMatcher(a=original, b=ported, autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        if tag == "equal":
            continue
        assert tag != "insert", f"{name}: lines added that replace nothing: {ported[j1:j2]}"
        unflagged = [n for n in range(i1 + 1, i2 + 1) if n not in flagged]
        assert not unflagged, (
            f"{name}: changed lines {unflagged} were not flagged by the port checker: "
            f"{[original[n - 1] for n in unflagged]}"
        )


@pytest.mark.timeout(120)
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_ported_program_runs_over_rclpy(name: str, ros: Any) -> None:
    servers, expected = PROGRAMS[name]
    for server in servers:
        ros.server(*server)
    result = run_program(PORTED / f"{name}.py")
    assert result.returncode == 0, result.stderr
    assert expected in result.stdout.splitlines()
    assert "Traceback" not in result.stderr
    assert "raised" not in result.stderr


@pytest.mark.timeout(120)
def test_ros2_style_program_runs_unchanged(ros: Any) -> None:
    ros.server("setbool", "port_setbool")
    ros.server("fibonacci", "port_fibonacci", "--step", "0.01")
    ros.server("publish", "/port_chatter", "--rate", "50")
    result = run_program(PORTING / "ros2" / "node_first.py")
    assert result.returncode == 0, result.stderr
    assert "outcome: done server node: port_ros2_intro" in result.stdout.splitlines()


def test_ros1_program_without_rospy_runs_unchanged() -> None:
    assert (ROS1 / "core_only.py").read_bytes() == (PORTED / "core_only.py").read_bytes()
    result = run_program(ROS1 / "core_only.py")
    assert result.returncode == 0, result.stderr
    assert "outcome: ok n: 4" in result.stdout


BLOCK_RCLPY = textwrap.dedent(
    """
    import sys

    class BlockRclpy:
        def find_spec(self, name, path=None, target=None):
            if name == "rclpy" or name.startswith("rclpy."):
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, BlockRclpy())
    """
)


def run_without_rclpy(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-W", "error", "-c", BLOCK_RCLPY + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=60,
        env=dict(os.environ, PYTHONPATH=str(SRC)),
        check=False,
    )


def test_import_smach_ros_works_where_rclpy_cannot_be_imported() -> None:
    result = run_without_rclpy(
        f"""
        import runpy
        import smach_ros
        assert "rclpy" not in sys.modules
        runpy.run_path({str(ROS1 / "core_only.py")!r}, run_name="__main__")
        """
    )
    assert result.returncode == 0, result.stderr
    assert "outcome: ok n: 4" in result.stdout


def test_a_ros_name_without_rclpy_raises_naming_the_extra() -> None:
    result = run_without_rclpy(
        """
        import smach_ros
        try:
            smach_ros.ConditionState
        except ModuleNotFoundError as exc:
            print("attribute:", exc)
        from smach_ros import *
        try:
            IntrospectionServer("name", None, "/SM_ROOT")
        except ModuleNotFoundError as exc:
            print("star:", exc)
        """
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2
    for line in lines:
        assert 'pip install "smach-planner[ros]"' in line
        assert "rclpy is missing" in line
