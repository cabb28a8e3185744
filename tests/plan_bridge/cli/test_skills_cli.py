"""`plan-bridge skills` and the skill map (skills.toml) through `check` and `run`."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from plan_bridge.cli import main

COURIER = Path(__file__).parents[2] / "plan_bridge" / "data" / "courier"

DRIVE_MAP = """\
# The courier's own drive; grabbing and releasing stay simulated.
[drive]
factory = "courier_skills:Drive"
arguments = ["?r", "?to"]
outcome_map = { arrived = "succeeded", blocked = "aborted" }
"""

DOMAIN_SETUP = """\
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.missions.mission import MissionSetup
from plan_bridge.skills.registry import SkillRegistry

from .courier_skills import Grab


def setup(task, *, seed, fail_rate):
    world = SimulatedWorld(task, seed=seed, fail_rate=fail_rate)
    skills = SkillRegistry()
    skills.add("grab", Grab)
    return MissionSetup(skills=symbolic_skills(world, skills), world=world)
"""


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A copy of the courier domain folder with DRIVE_MAP as its skills.toml."""
    target = tmp_path / "courier"
    shutil.copytree(COURIER, target, ignore=shutil.ignore_patterns("__pycache__", "*.log"))
    (target / "skills.toml").write_text(DRIVE_MAP, encoding="utf-8")
    return target


def test_skills_lists_each_action_with_its_parameters_and_where_it_runs(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["skills", str(folder)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [
        f"courier: 3 actions (problem p01.pddl; skill map: {folder / 'skills.toml'})",
        "drive(?r - robot, ?from - room, ?to - room)",
        "    your skill courier_skills:Drive(?r, ?to)  outcomes arrived->succeeded, "
        "blocked->aborted  [skills.toml:2]",
        "grab(?r - robot, ?p - parcel, ?x - room)",
        "    simulated (fallback)",
        "release(?r - robot, ?p - parcel, ?x - room)",
        "    simulated (fallback)",
        "1 from the skill map, 0 domain skills, 2 simulated",
    ]


def test_skills_json_tells_map_entries_domain_skills_variants_and_the_fallback_apart(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (folder / "__init__.py").write_text(DOMAIN_SETUP, encoding="utf-8")
    with (folder / "skills.toml").open("a", encoding="utf-8") as extra:
        extra.write('\n[[grab]]\nfactory = "courier_skills:make_gentle_grab"\nvariant = "gentle"\n')
    assert main(["skills", str(folder), "--problem", "p01", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["skill_map"] == str(folder / "skills.toml")
    assert data["problem"] == str(folder / "problems" / "p01.pddl")
    drive, grab, release = data["actions"]
    assert drive == {
        "action": "drive",
        "parameters": [
            {"name": "?r", "type": "robot"},
            {"name": "?from", "type": "room"},
            {"name": "?to", "type": "room"},
        ],
        "runs": "skill-map",
        "factory": "courier_skills:Drive",
        "line": 2,
        "arguments": ["?r", "?to"],
        "outcome_map": {"arrived": "succeeded", "blocked": "aborted"},
        "variants": [],
    }
    assert (grab["runs"], grab["factory"], grab["line"]) == (
        "domain",
        "courier.courier_skills:Grab",
        None,
    )
    assert grab["variants"] == [
        {
            "variant": "gentle",
            "runs": "skill-map",
            "factory": "courier_skills:make_gentle_grab",
            "line": 7,
            "arguments": None,
            "outcome_map": {},
        }
    ]
    assert (release["runs"], release["factory"]) == ("simulated", None)


def test_skills_of_a_bare_domain_file_lists_every_action_as_simulated(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = main(["skills", str(COURIER / "domain.pddl"), str(COURIER / "problems" / "p01.pddl")])
    assert code == 0
    out = capsys.readouterr().out
    assert "skill map: none" in out
    assert out.count("    simulated (fallback)") == 3


def test_skills_of_a_folder_without_python_does_not_import_unified_planning(
    folder: Path,
) -> None:
    script = textwrap.dedent(
        f"""
        import sys
        from plan_bridge.cli import main
        code = main(["skills", {str(folder)!r}])
        print("unified_planning loaded:", "unified_planning" in sys.modules)
        sys.exit(code)
        """
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, check=False
    )
    assert completed.returncode == 0, completed.stderr
    assert "your skill courier_skills:Drive" in completed.stdout
    assert "unified_planning loaded: False" in completed.stdout


def test_skills_reports_a_bad_map_with_its_file_and_line_and_exits_2(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (folder / "skills.toml").write_text(DRIVE_MAP.replace('"?to"]', '"?dest"]'), encoding="utf-8")
    assert main(["skills", str(folder)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(
        f"plan-bridge: error: {folder / 'skills.toml'}:4: [drive]: arguments: ?dest is not a "
        "parameter of drive"
    )


def test_check_fails_with_the_file_and_line_of_a_bad_map(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (folder / "skills.toml").write_text(
        DRIVE_MAP.replace("courier_skills:Drive", "courier_skills:Drvie"), encoding="utf-8"
    )
    assert main(["check", str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"{folder / 'skills.toml'}:3: [drive]: factory courier_skills:Drvie" in err
    assert "did you mean Drive?" in err
    assert "Traceback" not in err


def test_check_passes_a_folder_whose_map_fits_the_domain(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["check", str(folder)]) == 0
    assert "courier: OK" in capsys.readouterr().out


@pytest.mark.timeout(120)
def test_run_reaches_the_goal_with_the_drive_step_performed_by_the_mapped_skill(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["run", str(folder), "--fail-rate", "0", "--json", "--quiet"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0, report
    assert report["goal_reached"] is True
    assert report["executed"] == ["(drive rover lab store)", "(grab rover box store)"]
    # The mapped Drive ran (it logs next to its module) ...
    assert (folder / "skills.log").read_text(encoding="utf-8") == "drive rover store\n"
    # ... and the simulated grab after it found the robot in the store: the world
    # took the mapped skill's effects, so nothing failed and nothing was replanned.
    assert (report["actions_failed"], report["replans"]) == (0, 0)
