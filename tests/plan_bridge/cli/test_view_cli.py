"""`plan-bridge view` and `export` given a mission instead of a journal say what they
take and how to watch a mission."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.cli import main

FETCH = Path(__file__).parents[3] / "domains" / "fetch_drink"


@pytest.mark.parametrize("command", [["view"], ["view", "--check"], ["export", "--format", "dot"]])
@pytest.mark.parametrize("target", [FETCH, FETCH / "domain.pddl"], ids=["folder", "pddl"])
def test_a_mission_given_to_view_or_export_is_a_bad_input_error_that_says_what_to_run(
    command: list[str], target: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([command[0], str(target), *command[1:]]) == 2
    err = capsys.readouterr().err
    assert f"{target}: a mission, not a journal" in err
    assert "plan-bridge run TARGET --journal RUN.jsonl" in err
    assert "plan-bridge run TARGET --viewer" in err
