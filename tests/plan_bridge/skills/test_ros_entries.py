"""Skill-map entries for ROS 2 actions, services and topics: read and checked against
the message definitions, the folder's tables and the problem's objects, before
anything runs (no ROS graph is joined here: the generated classes describe
themselves)."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

import smach
from plan_bridge.pddl.task import ActionSchema, Parameter
from plan_bridge.skills.registry import SkillRegistry
from plan_bridge.skills.ros.conditions import parse_condition
from plan_bridge.skills.ros.entries import RosEntry
from plan_bridge.skills.ros.skill_states import RosCall, RosSkill
from plan_bridge.skills.ros.types import RosTypeError, install_hint, message_data
from plan_bridge.skills.skill_map import SkillMap, SkillMapError, load_skill_map


@dataclass(frozen=True)
class Task:
    """What a map is checked against: actions and the problem's objects."""

    actions: Mapping[str, ActionSchema]
    objects: Mapping[str, str]

    def objects_of_type(self, type_name: str) -> tuple[str, ...]:
        return tuple(name for name, kind in self.objects.items() if kind == type_name)


def schema(name: str, *parameters: tuple[str, str]) -> ActionSchema:
    return ActionSchema(name, tuple(Parameter(n, t) for n, t in parameters))


TASK = Task(
    {
        "drive": schema("drive", ("r", "robot"), ("from", "place"), ("to", "place")),
        "grip": schema("grip", ("r", "robot"), ("x", "parcel")),
        "confirm": schema("confirm", ("x", "parcel"), ("p", "place")),
    },
    {"bot": "robot", "hall": "place", "lab": "place", "box": "parcel"},
)
POSES = """
hall: {position: {x: 1.0, y: 2.0}, orientation: {w: 1.0}}
lab: {position: {x: 5.0, y: 2.5}, orientation: {w: 1.0}}
"""


def load(tmp_path: Path, text: str, task: Task = TASK) -> SkillMap:
    (tmp_path / "poses.yaml").write_text(POSES, encoding="utf-8")
    (tmp_path / "numbers.json").write_text('{"hall": 2, "lab": 3}', encoding="utf-8")
    path = tmp_path / "skills.toml"
    path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
    return load_skill_map(path, task)


def problems(tmp_path: Path, text: str, task: Task = TASK) -> list[str]:
    with pytest.raises(SkillMapError) as info:
        load(tmp_path, text, task)
    return [f"{p.line}: {p.message}" for p in info.value.problems]


def ros_of(skill_map: SkillMap, action: str) -> RosEntry:
    entry = skill_map.entry(action)
    assert entry is not None and entry.ros is not None
    return entry.ros


def test_an_action_entry_fills_its_goal_from_constants_arguments_and_a_table(
    tmp_path: Path,
) -> None:
    skill_map = load(
        tmp_path,
        """
        [drive]
        ros_action = "/{?r}/navigate"
        type = "test_msgs/action/Fibonacci"
        goal = { order = "numbers.json:?to" }
        timeout = 12.5
        feedback = ["sequence[0]"]
        """,
    )
    ros = ros_of(skill_map, "drive")
    assert (ros.kind, ros.timeout, ros.server_wait, ros.feedback) == (
        "action",
        12.5,
        10.0,
        ("sequence[0]",),
    )
    call = RosCall(ros, ("bot", "hall", "lab"))
    assert call.ros_name == "/bot/navigate"
    assert call.compose().order == 3


def test_a_service_request_takes_nested_fields_a_pose_from_yaml_and_object_names(
    tmp_path: Path,
) -> None:
    skill_map = load(
        tmp_path,
        """
        [drive]
        ros_service = "/set_pose"
        type = "nav_msgs/srv/SetMap"
        [drive.request]
        "initial_pose.header.frame_id" = "{?r}/map"
        "initial_pose.pose.pose" = "poses.yaml:?to"
        "map.info.width" = 4
        """,
    )
    request = RosCall(ros_of(skill_map, "drive"), ("bot", "hall", "lab")).compose()
    assert request.initial_pose.header.frame_id == "bot/map"
    assert request.initial_pose.pose.pose.position.x == 5.0
    assert request.initial_pose.pose.pose.orientation.w == 1.0
    assert request.map.info.width == 4
    assert message_data(request)["initial_pose"]["pose"]["pose"]["position"]["y"] == 2.5


def test_a_wrong_field_path_is_reported_at_its_line_with_the_fields_there(tmp_path: Path) -> None:
    found = problems(
        tmp_path,
        """
        [drive]
        ros_service = "/set_pose"
        type = "nav_msgs/srv/SetMap"
        [drive.request]
        "initial_pose.heder.frame_id" = "map"
        """,
    )
    assert found == [
        '5: [drive]: request "initial_pose.heder.frame_id": geometry_msgs/msg/'
        "PoseWithCovarianceStamped has no field 'heder' (did you mean header?); its fields: "
        "header, pose"
    ]


def test_a_type_that_is_not_installed_names_the_package_and_how_to_install_it(
    tmp_path: Path,
) -> None:
    (message,) = problems(
        tmp_path,
        """
        [drive]
        ros_action = "/navigate_to_pose"
        type = "nav2_msgs/action/NavigateToPose"
        """,
    )
    assert message.startswith(
        "3: [drive]: type nav2_msgs/action/NavigateToPose: the message package nav2_msgs is "
        "not installed; install it: pip install ros-jazzy-nav2-msgs"
    )
    assert "pip install ros-jazzy-nav2-msgs" in install_hint("nav2_msgs")


def test_a_table_without_an_entry_for_an_object_of_the_problem_is_reported(tmp_path: Path) -> None:
    task = Task(TASK.actions, {**TASK.objects, "office": "place"})
    (message,) = problems(
        tmp_path,
        """
        [drive]
        ros_action = "/drive"
        type = "test_msgs/action/Fibonacci"
        goal = { order = "numbers.json:?to" }
        """,
        task,
    )
    assert message == (
        '4: [drive]: goal "order": numbers.json has no entry for office (the objects of type '
        "place (?to)); its keys: hall, lab"
    )


def test_an_outcome_a_condition_gives_must_be_one_of_the_three_or_mapped(tmp_path: Path) -> None:
    found = problems(
        tmp_path,
        """
        [grip]
        ros_service = "/gripper"
        type = "std_srvs/srv/SetBool"
        request = { data = true }
        outcomes = { slipped = "success == false", succeded = "success == true" }
        outcome_map = { dropped = "aborted" }
        """,
    )
    assert found == [
        "5: [grip]: outcome 'slipped' is not one of succeeded, aborted, preempted; map it with "
        'outcome_map = { slipped = "aborted" } (or to another of them)',
        "5: [grip]: outcome 'succeded' is not one of succeeded, aborted, preempted (did you mean "
        'succeeded?); map it with outcome_map = { succeded = "aborted" } (or to another of them)',
        "6: [grip]: outcome_map names 'dropped', which no condition (outcomes) or status gives; "
        "outcomes of this entry: succeeded, aborted, preempted",
    ]


def test_every_mistake_of_the_map_is_reported_at_once_each_at_its_line(tmp_path: Path) -> None:
    found = problems(
        tmp_path,
        """
        [drive]
        ros_action = "/drive"
        type = "std_srvs/srv/SetBool"
        timeout = -1
        [grip]
        ros_service = "/gripper"
        type = "std_srvs/srv/SetBool"
        request = { data = "yes", reason = "?y" }
        outcomes = { aborted = "success = false" }
        server_wait = "soon"
        [confirm]
        ros_topic = "/receipts"
        type = "std_msgs/msg/String"
        goal = { data = "x" }
        outcomes = { succeeded = "data == ?q" }
        """,
    )
    assert found == [
        "3: [drive]: type std_srvs/srv/SetBool is a service, but this entry needs an action "
        "(PACKAGE/action/NAME)",
        "4: [drive]: timeout must be a number of seconds > 0, got -1 (an integer)",
        '10: [grip]: server_wait must be a number of seconds > 0, got "soon" (a string)',
        "8: [grip]: request \"data\": a boolean field needs true or false, got 'yes'",
        "8: [grip]: request \"reason\": std_srvs/srv/SetBool request has no field 'reason'; its "
        "fields: data",
        "9: [grip]: outcomes: aborted: condition 'success = false': cannot read '= false'; write "
        'FIELD OP VALUE, VALUE a number, true, false, a "quoted string" or ?param',
        "14: [confirm]: unknown key 'goal' for a ros_topic entry (a topic is only listened to: "
        "nothing is sent); allowed keys: ros_topic, type, outcomes, outcome_map, timeout, variant",
        "15: [confirm]: outcomes: succeeded: condition 'data == ?q': ?q is not a parameter of the "
        "action; parameters: ?x, ?p",
    ]


def test_a_ros_key_with_a_factory_or_a_misspelled_ros_key_is_refused(tmp_path: Path) -> None:
    found = problems(
        tmp_path,
        """
        [drive]
        factory = "x:y"
        ros_action = "/drive"
        type = "test_msgs/action/Fibonacci"
        [grip]
        ros_servce = "/gripper"
        type = "std_srvs/srv/SetBool"
        """,
    )
    assert found[0] == (
        "2: [drive]: ros_action and factory in one entry; an entry runs one thing: a factory, "
        "a ros_action, a ros_service or a ros_topic"
    )
    assert found[1].startswith("6: [grip]: unknown key 'ros_servce' (did you mean ros_service?)")
    assert len(found) == 3 and found[2].startswith("7: [grip]: unknown key 'type'")


def test_a_name_of_an_object_cannot_fill_a_number_field_without_a_table(tmp_path: Path) -> None:
    (message,) = problems(
        tmp_path,
        """
        [drive]
        ros_action = "/drive"
        type = "test_msgs/action/Fibonacci"
        goal = { order = "?to" }
        """,
    )
    assert message == (
        '4: [drive]: goal "order": ?to is an object name (text), but the field is a int32; '
        'look its value up in a table of the folder instead: "TABLE.yaml:?to"'
    )


def test_conditions_compare_fields_with_constants_and_arguments() -> None:
    from std_msgs.msg import String
    from test_msgs.action import Fibonacci

    result = Fibonacci.Result(sequence=[3, 5])
    condition = parse_condition(
        "sequence[0] == 3 and sequence[1] > 4 or sequence[0] < 0", Fibonacci.Result, ["to"]
    )
    assert condition.holds(result, {}) is True
    assert condition.holds(Fibonacci.Result(sequence=[]), {}) is False  # no item: false
    receipt = parse_condition('data == "at {?p}"', String, ["x", "p"])
    assert receipt.holds(String(data="at lab"), {"p": "lab"}) is True
    assert (
        parse_condition("data != ?x", String, ["x"]).holds(String(data="box"), {"x": "box"})
        is False
    )
    with pytest.raises(
        RosTypeError, match="sequence is a sequence<int32> field, compared with a number"
    ):
        parse_condition("sequence == 3", Fibonacci.Result, [])


def test_the_skill_of_an_entry_is_a_machine_with_its_outcomes_built_without_ros(
    tmp_path: Path,
) -> None:
    skill_map = load(
        tmp_path,
        """
        [drive]
        ros_action = "/courier/drive"
        type = "test_msgs/action/Fibonacci"
        goal = { order = "numbers.json:?to" }
        outcomes = { off-route = "sequence[0] == 0" }
        outcome_map = { off-route = "aborted" }
        """,
    )
    registry = skill_map.apply(SkillRegistry())
    skill = registry.get("drive")
    assert skill is not None and isinstance(skill.factory, RosSkill)
    machine = skill.factory("bot", "hall", "lab")
    assert isinstance(machine, smach.StateMachine)
    assert set(machine.get_registered_outcomes()) == {
        "succeeded",
        "aborted",
        "preempted",
        "off-route",
    }
    assert list(machine.get_children()) == ["DRIVE"]
    assert skill.outcome_problems(machine) == [] and skill.outcome_warnings(machine) == []


def test_mistakes_in_tables_statuses_and_feedback_are_reported_at_their_lines(
    tmp_path: Path,
) -> None:
    found = problems(
        tmp_path,
        """
        [drive]
        ros_action = "/drive"
        type = "test_msgs/action/Fibonacci"
        goal = { order = "missing.yaml:?to" }
        status = { cancelled = "aborted" }
        feedback = ["sequense"]
        [grip]
        ros_service = "/set_pose"
        type = "nav_msgs/srv/SetMap"
        request = { "initial_pose.pose.pose" = "poses.yaml:attic" }
        """,
    )
    assert found[0].startswith(
        "5: [drive]: status: 'cancelled' is not a terminal status (did you mean canceled?)"
    )
    assert found[1].startswith(
        f'4: [drive]: goal "order": no table file {tmp_path / "missing.yaml"}'
    )
    assert found[2].startswith(
        "6: [drive]: feedback \"sequense\": test_msgs/action/Fibonacci feedback has no field 'sequense' (did you mean sequence?)"
    )
    assert (
        found[3]
        == '10: [grip]: request "initial_pose.pose.pose": poses.yaml has no entry for attic (the key); its keys: hall, lab'
    )
    assert len(found) == 4


def test_a_table_value_that_does_not_fit_the_field_is_reported(tmp_path: Path) -> None:
    (message,) = problems(
        tmp_path,
        """
        [drive]
        ros_service = "/set_pose"
        type = "nav_msgs/srv/SetMap"
        request = { "initial_pose.pose.pose.position" = "poses.yaml:?to" }
        """,
    )
    assert message == (
        '4: [drive]: request "initial_pose.pose.pose.position": poses.yaml: hall: '
        "geometry_msgs/msg/Point has no field 'position'; its fields: x, y, z"
    )


def test_the_guides_example_map_is_only_refused_for_the_missing_nav2_msgs(tmp_path: Path) -> None:
    guide = (Path(__file__).parents[3] / "docs" / "plan-bridge.md").read_text(encoding="utf-8")
    section = guide[guide.index("### ROS 2 entries") :]
    block = section.split("```toml\n", 1)[1].split("```", 1)[0]
    task = Task(
        {
            **TASK.actions,
            "close-gripper": schema("close-gripper", ("r", "robot")),
            "wait-docked": schema("wait-docked", ("r", "robot"), ("d", "place")),
        },
        TASK.objects,
    )
    (message,) = problems(tmp_path, block, task)
    assert (
        "[drive]: type nav2_msgs/action/NavigateToPose: the message package nav2_msgs is not installed"
        in message
    )
