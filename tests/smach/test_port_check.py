"""smach.port_check: static findings, with line numbers, for porting SMACH programs."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from smach.port_check import CHANGE, DIFFERS, NOTE, Finding, check_file, check_source, main

ROS1 = Path(__file__).parent / "ros" / "porting" / "ros1"


def findings(code: str) -> list[Finding]:
    return check_source(textwrap.dedent(code), "prog.py")


def at(found: list[Finding], line: int, topic: str) -> list[Finding]:
    return [f for f in found if f.line == line and f.topic == topic]


def test_rospy_calls_are_listed_with_their_rclpy_equivalent() -> None:
    found = findings(
        """\
        import rospy
        rospy.init_node('robot')
        rospy.sleep(1.0)
        if rospy.is_shutdown():
            pass
        """
    )
    assert [(f.line, f.kind) for f in found] == [
        (1, CHANGE),
        (2, CHANGE),
        (3, CHANGE),
        (4, CHANGE),
    ]
    assert "rclpy.create_node" in found[1].suggestion
    assert "time.sleep" in found[2].suggestion
    assert found[3].suggestion == "not rclpy.ok()"


def test_rospy_imported_under_another_name_is_followed() -> None:
    found = findings("import rospy as rp\nrp.loginfo('x')\n")
    assert at(found, 2, "rospy")[0].message == "rospy.loginfo is ROS 1"


def test_actionlib_message_types_and_goal_status_codes_are_listed() -> None:
    found = findings(
        """\
        from actionlib_msgs.msg import GoalStatus
        from my_robot.msg import DockAction, DockGoal
        goal = DockGoal(speed=1)
        ok = status == GoalStatus.SUCCEEDED
        gone = status == GoalStatus.PREEMPTED
        """
    )
    assert "action_msgs" in at(found, 1, "actionlib")[0].suggestion
    assert {f.suggestion for f in at(found, 2, "actionlib")} == {
        "from my_robot.action import Dock; use Dock",
        "from my_robot.action import Dock; use Dock.Goal",
    }
    assert at(found, 3, "actionlib")[0].suggestion == "Dock.Goal"
    assert "STATUS_SUCCEEDED" in at(found, 4, "actionlib")[0].suggestion
    assert "STATUS_CANCELED" in at(found, 5, "actionlib")[0].suggestion


def test_service_request_classes_are_listed() -> None:
    found = findings(
        "from std_srvs.srv import SetBool, SetBoolRequest\nSetBoolRequest(data=True)\n"
    )
    assert "SetBool.Request" in at(found, 1, "rospy")[0].suggestion
    assert at(found, 2, "actionlib")[0].suggestion == "SetBool.Request"


def test_undeclared_userdata_write_in_a_state_class_is_a_change() -> None:
    found = findings(
        """\
        import smach

        class Detect(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=['found'], input_keys=['image'])

            def execute(self, ud):
                seen = ud.image
                ud.pose = (1, 2)
                ud['score'] = 0.5
                return 'found'
        """
    )
    userdata = [f for f in found if f.topic == "userdata"]
    assert [(f.line, f.kind) for f in userdata] == [(9, CHANGE), (10, CHANGE)]
    assert "'pose'" in userdata[0].message and "output_keys" in userdata[0].suggestion
    assert "'score'" in userdata[1].message


def test_undeclared_read_and_write_through_an_input_only_key_are_listed() -> None:
    found = findings(
        """\
        import smach

        class Move(smach.State):
            def __init__(self):
                super().__init__(outcomes=['done'], input_keys=['target'])

            def execute(self, userdata):
                userdata.target.x = 3
                return 'done' if userdata.speed else 'done'
        """
    )
    userdata = [f for f in found if f.topic == "userdata"]
    assert [f.line for f in userdata] == [8, 9]
    assert "io_keys" in userdata[0].suggestion
    assert "'speed'" in userdata[1].message and "input_keys" in userdata[1].suggestion


def test_cbstate_callbacks_are_checked_against_the_state_and_decorator_keys() -> None:
    found = findings(
        """\
        import smach

        @smach.cb_interface(input_keys=['a'], outcomes=['ok'])
        def step(ud):
            ud.b = ud.a
            ud.c = 1
            return 'ok'

        state = smach.CBState(step, output_keys=['b'])
        """
    )
    userdata = [f for f in found if f.topic == "userdata"]
    assert [(f.line, f.message.split("'")[1]) for f in userdata] == [(6, "c")]


def test_keys_built_at_run_time_are_not_guessed() -> None:
    found = findings(
        """\
        import smach
        KEYS = ['a']

        class S(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=['ok'], output_keys=KEYS)

            def execute(self, ud):
                ud.b = 1
                return 'ok'
        """
    )
    assert [f for f in found if f.topic == "userdata"] == []


def test_transition_to_an_undefined_state_says_what_to_change() -> None:
    found = findings(
        """\
        import smach
        sm = smach.StateMachine(outcomes=['done'])
        with sm:
            smach.StateMachine.add('A', a, transitions={'ok': 'B', 'fail': 'MISING'})
            smach.StateMachine.add('B', b, transitions={'ok': 'done'})
        """
    )
    construction = [f for f in found if f.topic == "construction"]
    assert len(construction) == 1
    finding = construction[0]
    assert (finding.line, finding.kind) == (4, CHANGE)
    assert "'MISING'" in finding.message and "InvalidTransitionError" in finding.message
    assert "A, B, done" in finding.suggestion


def test_nested_machines_are_checked_against_their_own_labels() -> None:
    found = findings(
        """\
        import smach
        outer = smach.StateMachine(['done'])
        inner = smach.StateMachine(['finished'])
        with outer:
            smach.StateMachine.add('SUB', inner, transitions={'finished': 'done'})
            with inner:
                smach.StateMachine.add('X', x, transitions={'ok': 'finished'})
        """
    )
    assert [f for f in found if f.topic == "construction"] == []


def test_bare_string_outcomes_are_a_change() -> None:
    found = findings("import smach\nsmach.State(outcomes='done')\n")
    assert found[0].suggestion == "outcomes=['done']"


def test_ros1_signature_and_introspection_are_notes_and_differences() -> None:
    found = findings(
        """\
        import smach_ros
        s = smach_ros.ServiceState('set', SetBool)
        c = smach_ros.ConditionState(cond, poll_rate=0.1)
        n = smach_ros.ConditionState(node, cond)
        sis = smach_ros.IntrospectionServer('srv', sm, '/SM_ROOT')
        """
    )
    assert [(f.line, f.kind) for f in found] == [(2, NOTE), (3, NOTE), (5, DIFFERS)]


def test_moved_modules_are_listed() -> None:
    found = findings(
        "from smach_ros.util import set_preempt_handler\nimport smach_msgs.msg\nimport roslib\n"
    )
    assert [(f.line, f.topic) for f in found] == [(1, "moved"), (2, "moved"), (3, "moved")]
    assert found[0].suggestion == "import from smach_ros (set_preempt_handler)"


def test_python2_source_is_reported_and_still_scanned_for_ros1_lines() -> None:
    found = findings("import rospy\nprint 'hello'\nrospy.spin()\n")
    assert found[0].topic == "syntax" and found[0].line == 2
    assert [f.line for f in found[1:]] == [1, 3]


@pytest.mark.parametrize("path", sorted(ROS1.glob("*.py")), ids=lambda p: p.stem)
def test_every_ros1_fixture_is_checked(path: Path) -> None:
    found = check_file(path)
    has_rospy = "import rospy" in path.read_text()
    assert any(f.topic == "rospy" and f.kind == CHANGE for f in found) == has_rospy


def test_cli_exit_status_and_summary(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    clean = tmp_path / "clean.py"
    clean.write_text("import smach\n")
    assert main([str(clean)]) == 0
    assert capsys.readouterr().out.strip() == "0 findings in 1 file"

    ros1 = tmp_path / "ros1.py"
    ros1.write_text("import rospy\n")
    assert main([str(clean), str(ros1)]) == 1
    out = capsys.readouterr().out
    assert f"{ros1}:1:1: change [rospy] rospy is ROS 1" in out
    assert out.strip().endswith("1 finding in 2 files (1 change)")

    assert main([str(tmp_path / "missing.py")]) == 2
    assert "missing.py: cannot read" in capsys.readouterr().err


def test_cli_json_lines(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ros1 = tmp_path / "ros1.py"
    ros1.write_text("import rospy\nrospy.spin()\n")
    assert main(["--json", str(ros1)]) == 1
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [(r["line"], r["kind"], r["topic"]) for r in records] == [
        (1, "change", "rospy"),
        (2, "change", "rospy"),
    ]


def test_runs_as_a_module() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "smach.port_check", str(ROS1 / "core_only.py")],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "0 findings in 1 file"
