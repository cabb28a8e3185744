"""`plan-bridge run --control` and `plan-bridge control`: operating a mission from a terminal."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from controlled_mission import ControlledMission, control

from plan_bridge.cli import main
from smach.introspection.journal import read_journal

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = pytest.mark.timeout(180)


class Mission(ControlledMission):
    """`plan-bridge run ROOMS --control --journal JOURNAL --json ...` in a subprocess."""

    def __init__(self, journal: Path, *extra: str) -> None:
        super().__init__(str(ROOMS), "--control", "--journal", str(journal), "--json", *extra)


@pytest.fixture
def missions() -> Iterator[list[Mission]]:
    started: list[Mission] = []
    yield started
    for mission in started:
        mission.end()


def wait_status(capsys: pytest.CaptureFixture[str], url: str, text: str) -> str:
    """Poll `control URL status` until its output holds ``text`` (60 s at most)."""
    deadline = time.monotonic() + 60
    out = ""
    while time.monotonic() < deadline:
        out = control(capsys, url, "status")[1]
        if text in out:
            break
        time.sleep(0.05)
    return out


def test_a_mission_started_paused_is_stepped_resumed_and_journaled(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    journal = tmp_path / "run.jsonl"
    mission = Mission(journal, "--start-paused")
    missions.append(mission)
    code, out, _ = control(capsys, mission.url, "status")
    assert code == 0 and out.startswith("control: paus")
    code, out, _ = control(capsys, mission.url, "break", "*/03_*")
    assert code == 0
    code, out, _ = control(capsys, mission.url, "resume")
    assert code == 0
    # The mission runs to its third step and holds there.
    out = wait_status(capsys, mission.url, "at breakpoint")
    assert "at breakpoint /ROOT/PLAN/03_" in out
    assert control(capsys, mission.url, "break", "*/03_*")[0] == 0  # toggled off
    assert control(capsys, mission.url, "resume")[0] == 0
    mission.finish()
    assert json.loads(mission.stdout)["goal_reached"] is True
    _, records = read_journal(journal)
    actions = [(r["action"], r["source"]) for r in records if r.get("kind") == "control"]
    assert actions[0] == ("pause", "cli")
    assert ("add_breakpoint", "cli") in actions and ("breakpoint_hit", "machine") in actions
    assert ("remove_breakpoint", "cli") in actions and actions[-1] == ("resume", "cli")


def test_abort_from_the_cli_ends_the_mission_aborted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    mission = Mission(tmp_path / "run.jsonl", "--break", "*/02_*")
    missions.append(mission)
    assert "at breakpoint" in wait_status(capsys, mission.url, "at breakpoint")
    code, out, _ = control(capsys, mission.url, "abort", "operator test")
    assert code == 0 and "aborted by the operator (cli): operator test" in out
    # The abort preempts the plan, which releases the held step: no resume needed.
    mission.finish()
    result = json.loads(mission.stdout)
    assert result["outcome"] == "aborted" and not result["goal_reached"]
    assert result["explanation"] == "aborted by the operator (cli): operator test"


def test_refusals_and_bad_input_have_clear_messages(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], missions: list[Mission]
) -> None:
    mission = Mission(tmp_path / "run.jsonl", "--start-paused")
    missions.append(mission)
    code, _, err = control(capsys, mission.url, "force", "succeeded")
    assert code == 1 and "refused: force_outcome: no state is running" in err
    code, _, err = control(capsys, mission.url, "break")
    assert code == 2 and "break needs PATTERN" in err
    code, _, err = control(capsys, mission.url.split("#")[0], "pause")
    assert code == 2 and "no #token=" in err
    code, _, err = control(capsys, mission.url.replace("token=", "token=x"), "pause")
    assert code == 2 and "wrong control token" in err
    assert control(capsys, mission.url, "resume")[0] == 0
    mission.finish()
    assert json.loads(mission.stdout)["goal_reached"] is True
    code, _, err = control(capsys, mission.url, "status")
    assert code == 2 and "no run answers" in err


def test_run_refuses_a_malformed_breakpoint(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["run", str(ROOMS), "--break", "PICK"])
    assert exit_info.value.code == 2
    assert "neither a state path nor a pattern" in capsys.readouterr().err
