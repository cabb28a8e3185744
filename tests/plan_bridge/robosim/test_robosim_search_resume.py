"""A search killed after a checkpoint that holds a place ruled out, ``(absent soda
PLACE)``, resumes with ``plan-bridge run --resume`` and ends as the uninterrupted run:
found and fetched, or not found naming the same places (issue 36)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.cli import main

SEARCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_search"
#: What a resumed run must end with as the uninterrupted one did.
END = ("outcome", "goal_reached", "explanation", "world_changes", "distance_m")

pytestmark = pytest.mark.timeout(300)


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, dict[str, Any]]:
    code = main(["run", *args, "--quiet", "--json"])
    data: dict[str, Any] = json.loads(capsys.readouterr().out)
    return code, data


def _cut_after_a_place_ruled_out(journal: Path, killed: Path) -> None:
    """``killed``: ``journal`` up to the end of its first checkpoint with an absence."""
    data = journal.read_bytes()
    at = data.index(b"(absent soda ", data.index(b'{"kind": "checkpoint"'))
    killed.write_bytes(data[: data.index(b"\n", at) + 1])


@pytest.mark.parametrize(
    ("events", "seed", "code"), [("moved", 3, 0), ("taken", 2, 1)], ids=["found", "not_found"]
)
def test_a_search_killed_after_a_place_ruled_out_resumes_to_the_same_end(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], events: str, seed: int, code: int
) -> None:
    journal = tmp_path / "run.jsonl"
    events_file = str(SEARCH / "events" / f"{events}.yaml")
    whole_code, whole = _run(
        capsys, str(SEARCH), "--events", events_file, "--seed", str(seed),
        "--journal", str(journal),
    )  # fmt: skip
    assert whole_code == code
    killed = tmp_path / "killed.jsonl"
    _cut_after_a_place_ruled_out(journal, killed)
    resumed_code, resumed = _run(capsys, "--resume", str(killed))
    assert resumed_code == code
    assert {k: resumed[k] for k in END} == {k: whole[k] for k in END}
    if code:
        assert resumed["explanation"].startswith("soda not found")
