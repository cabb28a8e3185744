"""States without a node (the ROS 1 signature) and the default node.

Each test runs a short program in a fresh process: the default node lives in
rclpy's default context and initialises rclpy on demand, which only a process
that has not touched rclpy yet can show.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

SRC = Path(__file__).parents[3] / "src"


def run(code: str) -> subprocess.CompletedProcess[str]:
    program = "import smach, smach_ros\nimport smach.ros._api\n" + textwrap.dedent(code)
    return subprocess.run(
        [sys.executable, "-W", "error", "-c", program],
        capture_output=True,
        text=True,
        timeout=60,
        env=dict(os.environ, PYTHONPATH=str(SRC)),
        check=False,
    )


def assert_ran(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    return result.stdout.splitlines()


@pytest.mark.timeout(90)
def test_states_without_a_node_share_one_default_node_created_on_demand() -> None:
    lines = assert_ran(
        run(
            """
            import os
            import rclpy
            from std_msgs.msg import String

            assert not rclpy.ok()
            cond = smach_ros.ConditionState(lambda ud: True)
            assert cond.node.context.ok(), "rclpy initialised on demand"
            assert not rclpy.ok(), "in a context of smach's own: rclpy.init() stays possible"
            monitor = smach_ros.MonitorState("/port_default", String, lambda ud, m: True)
            keyword = smach_ros.ConditionState(node=None, cond_cb=lambda ud: True)
            assert cond.node is monitor.node is keyword.node is smach_ros.default_node()
            assert cond.node.get_name() == f"smach_ros_{os.getpid()}"
            print(cond.execute(smach.UserData()))
            """
        )
    )
    assert lines == ["true"]


@pytest.mark.timeout(90)
def test_shutdown_default_node_shuts_down_the_rclpy_smach_started() -> None:
    lines = assert_ran(
        run(
            """
            import rclpy

            first = smach_ros.default_node()
            smach_ros.shutdown_default_node()
            print(first.context.ok())
            again = smach_ros.ConditionState(lambda ud: False)
            print(again.node.context.ok(), again.node is not first)
            print(again.execute(smach.UserData()))
            rclpy.init()  # the program's own init still works
            print(rclpy.ok())
            rclpy.shutdown()
            """
        )
    )
    assert lines == ["False", "True True", "false", "True"]


@pytest.mark.timeout(90)
def test_rclpy_initialised_by_the_program_is_left_to_the_program() -> None:
    lines = assert_ran(
        run(
            """
            import rclpy

            rclpy.init()
            node = smach_ros.default_node()
            print(node.context is rclpy.get_default_context())
            smach_ros.shutdown_default_node()
            print(rclpy.ok())
            rclpy.shutdown()
            """
        )
    )
    assert lines == ["True", "True"]


@pytest.mark.timeout(90)
def test_condition_state_poll_rate_is_a_period_in_the_ros1_form_and_hz_with_a_node() -> None:
    lines = assert_ran(
        run(
            """
            import rclpy
            from rclpy.duration import Duration

            rclpy.init()
            ros1 = smach_ros.ConditionState(lambda ud: True, [], 0.5)
            ros1_duration = smach_ros.ConditionState(lambda ud: True, poll_rate=Duration(seconds=0.25))
            node = rclpy.create_node("port_condition_node")
            ros2 = smach_ros.ConditionState(node, lambda ud: True, poll_rate=4.0)
            default = smach_ros.ConditionState(node, lambda ud: True)
            print(ros1._period, ros1_duration._period, ros2._period, default._period)
            try:
                smach_ros.ConditionState(lambda ud: True, poll_rate=0)
            except smach.InvalidStateError as exc:
                print(exc)
            node.destroy_node()
            rclpy.shutdown()
            """
        )
    )
    assert lines == [
        "0.5 0.25 0.25 0.05",
        "ConditionState: poll_rate must be > 0 s (ROS 1 form: a period), got 0",
    ]


@pytest.mark.timeout(90)
def test_introspection_server_is_a_node_and_initialises_rclpy_on_demand() -> None:
    lines = assert_ran(
        run(
            """
            import rclpy
            from rclpy.node import Node
            from smach.testing import ScriptedState

            sm = smach.StateMachine(outcomes=["done"])
            sm.add("A", ScriptedState(["done"]))
            sis = smach_ros.IntrospectionServer("/port/intro_demo", sm, "/SM_ROOT")
            print(isinstance(sis, Node), sis.get_name(), sis.status_topic)
            context = sis.context
            sis.start()
            print(sm.execute())
            sis.stop()
            sis.destroy_node()
            smach_ros.shutdown_default_node()
            print(context.ok())
            try:
                smach_ros.IntrospectionServer("bad-name", sm, "/SM_ROOT")
            except smach.InvalidStateError as exc:
                print(str(exc).split(":")[0])
            """
        )
    )
    assert lines == [
        "True port_intro_demo /port/intro_demo/smach/container_status",
        "done",
        "False",
        "introspection server name 'bad-name' is not a valid ROS topic name (letters, digits, '_' and '/')",
    ]
