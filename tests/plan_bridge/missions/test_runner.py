"""The mission runner, and domain folders whose Python adds a user's skill to
simulated ones (run through `plan-bridge run`, the runner and the Executive alike)."""

from __future__ import annotations

import json
import shutil
import textwrap
from pathlib import Path

import pytest

from plan_bridge.cli import main
from plan_bridge.missions.mission import load_target
from plan_bridge.missions.runner import (
    DEFAULT_FAIL_RATE,
    MissionError,
    MissionOptions,
    prepare_mission,
)

DATA = Path(__file__).parents[1] / "data"
DOMAINS = Path(__file__).parents[3] / "domains"

#: A user's domain package: its own drive skill, every other action symbolic.
CLASSICAL_SETUP = """\
import smach
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.skills.registry import SkillRegistry


class Drive(smach.State):
    # (a real skill would command the base here)
    def __init__(self, bot, origin, goal):
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])

    def execute(self, ud):
        return "succeeded"


def setup(task, *, seed, fail_rate):
    world = SimulatedWorld(task, seed=seed, fail_rate=fail_rate)
    mine = SkillRegistry()
    mine.add("drive", Drive)
    return MissionSetup(symbolic_skills(world, mine), world=world)
"""

#: The same for a temporal domain: a user's durative drive beside timed skills; it
#: aborts its first drive without saying anything.
TEMPORAL_SETUP = """\
import smach
from plan_bridge.execution.timed_world import TimedWorld, timed_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.skills.registry import SkillRegistry

DRIVES = []


class Drive(smach.State):
    def __init__(self, rover, origin, goal):
        super().__init__(outcomes=["succeeded", "aborted", "preempted"])

    def execute(self, ud):
        DRIVES.append(1)
        return "aborted" if len(DRIVES) == 1 else "succeeded"


def setup(task, *, seed, fail_rate):
    world = TimedWorld(task, seed=seed, fail_rate=fail_rate)
    mine = SkillRegistry()
    mine.add("drive", Drive)
    return MissionSetup(timed_skills(world, mine), world=world)
"""


def user_folder(tmp_path: Path, domain: str, code: str) -> Path:
    folder = tmp_path / domain
    shutil.copytree(DATA / domain, folder)
    (folder / "__init__.py").write_text(textwrap.dedent(code))
    return folder


def run_json(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, dict[str, object]]:
    code = main(["run", *args, "--quiet", "--json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("fail_rate", "seed"), [("0", "0"), ("0.3", "1"), ("0.3", "2")])
def test_a_domain_folder_with_a_user_skill_reaches_the_goal_from_the_cli(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fail_rate: str, seed: str
) -> None:
    folder = user_folder(tmp_path, "warehouse_bot", CLASSICAL_SETUP)
    code, data = run_json(capsys, str(folder), "--fail-rate", fail_rate, "--seed", seed)
    assert code == 0, data["explanation"]
    assert data["goal_reached"] is True


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("fail_rate", "seed"), [("0", "0"), ("0.3", "3")])
def test_a_temporal_folder_whose_user_skill_aborts_replans_and_reaches_the_goal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fail_rate: str, seed: str
) -> None:
    folder = user_folder(tmp_path, "timed_rover", TEMPORAL_SETUP)
    code, data = run_json(capsys, str(folder), "--fail-rate", fail_rate, "--seed", seed)
    assert code == 0, data["explanation"]
    assert data["actions_failed"] >= 1  # the user's first drive
    decisions = [d["decision"] for d in data["decisions"]]  # type: ignore[attr-defined]
    assert "sense" in decisions


@pytest.mark.timeout(120)
def test_prepare_mission_uses_the_cli_defaults() -> None:
    with_skills = prepare_mission(load_target(DOMAINS / "recharge"))
    assert with_skills.fail_rate == DEFAULT_FAIL_RATE
    assert with_skills.planner.name == "auto"
    bare = prepare_mission(
        load_target(
            DATA / "warehouse_bot" / "domain.pddl", DATA / "warehouse_bot" / "problems" / "p01.pddl"
        )
    )
    assert bare.fail_rate == 0.0
    assert bare.world is not None and bare.executive.world is bare.world


@pytest.mark.timeout(120)
def test_a_prepared_mission_runs_and_reports_the_numbers_of_run_json() -> None:
    mission = prepare_mission(load_target(DOMAINS / "recharge"), MissionOptions(seed=3))
    assert mission.run() == "succeeded"
    figures = mission.figures()
    assert figures["goal_reached"] is True
    assert figures["target"] == "recharge" and figures["seed"] == 3
    assert {"faults_injected", "sim_time_s", "explanation", "executed"} <= set(figures)


def test_a_bad_policy_is_a_mission_error_naming_the_choices() -> None:
    with pytest.raises(MissionError, match="full"):
        prepare_mission(load_target(DOMAINS / "recharge"), MissionOptions(policy="sometimes"))


@pytest.mark.timeout(120)
def test_a_mission_that_ends_without_its_goal_says_why_even_when_quiet(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = shutil.copytree(DATA / "warehouse_bot", tmp_path / "blocked")
    problem = folder / "problems" / "p01.pddl"
    problem.write_text(
        problem.read_text().replace("(aisle aisle-a racks) (aisle racks aisle-a)", "")
    )
    code = main(["run", str(folder), "--quiet"])
    err = capsys.readouterr().err
    assert code == 1
    assert "goal not reached: no plan (unsolvable)" in err


ROVER_SKILL = """\
import smach


class Drive(smach.State):
    # The user's drive, bound by skills.toml; reports where the rover ended up.
    def __init__(self, rover, goal):
        super().__init__(outcomes=["arrived", "stuck", "preempted"], output_keys=["observations"])
        self.rover, self.goal = rover, goal

    def execute(self, ud):
        ud.observations = {f"(parked {self.rover} {self.goal})": True}
        return "arrived"
"""

ROVER_MAP = """\
[drive]
factory = "rover_skills:Drive"
arguments = ["?r", "?to"]
outcome_map = { arrived = "succeeded", stuck = "aborted" }
"""


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("fail_rate", "seed"), [("0", "0"), ("0.3", "2")])
def test_a_temporal_folder_with_a_skill_map_reaches_the_goal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fail_rate: str, seed: str
) -> None:
    folder = shutil.copytree(DATA / "timed_rover", tmp_path / "rover")
    (folder / "rover_skills.py").write_text(ROVER_SKILL)
    (folder / "skills.toml").write_text(ROVER_MAP)
    code, data = run_json(capsys, str(folder), "--fail-rate", fail_rate, "--seed", seed)
    assert code == 0, data["explanation"]
    assert "(drive rv base ridge)" in data["executed"]  # type: ignore[operator]


NAVIGATE = """\
import smach


def navigate(robot, origin, destination):
    def drive(ud):
        ud.observations = {f"(at {robot} {destination})": True}
        return "succeeded"

    return smach.CBState(
        drive, outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
    )
"""


@pytest.mark.timeout(300)
@pytest.mark.parametrize("seed", ["0", "1"])
def test_a_skill_map_replaces_a_domain_s_simulated_skill_and_the_mission_succeeds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], seed: str
) -> None:
    folder = shutil.copytree(DOMAINS / "fetch_drink", tmp_path / "fetch")
    (folder / "my_nav.py").write_text(NAVIGATE)
    (folder / "skills.toml").write_text('navigate = "my_nav:navigate"\n')
    mission = prepare_mission(load_target(folder), MissionOptions(seed=int(seed), fail_rate=0.3))
    skill = mission.setup.skills.get("navigate")
    assert skill is not None and not skill.simulated
    code, data = run_json(capsys, str(folder), "--fail-rate", "0.3", "--seed", seed)
    assert code == 0, data["explanation"]
