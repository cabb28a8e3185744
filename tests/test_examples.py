"""Every example and the README's code block run and do what they say."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


@pytest.mark.timeout(120)
@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_to_success(example: Path) -> None:
    result = subprocess.run(
        [sys.executable, str(example)], capture_output=True, text=True, timeout=110, cwd=ROOT
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip(), "an example should show what it did"


def test_hierarchical_demo_reports_outcome_and_transitions() -> None:
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "hierarchical_demo.py"), "--seed", "2"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert "outcome: mission_complete" in result.stdout
    assert "PATROL --low_battery--> RECHARGE" in result.stdout
    assert "RECHARGE --charged--> PATROL" in result.stdout


def test_readme_python_example_prints_what_its_comment_says() -> None:
    text = (ROOT / "README.md").read_text()
    block = re.search(r"```python\n(.*?)```", text, re.S)
    assert block is not None
    code = block.group(1)
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == "done cup"
    assert "stateDiagram-v2" in result.stdout
