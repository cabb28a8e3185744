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


@pytest.mark.timeout(120)
def test_the_first_skill_block_of_the_plan_bridge_guide_runs_and_reaches_the_goal() -> None:
    text = (ROOT / "docs" / "plan-bridge.md").read_text()
    section = text[text.index("## Your first skill") :]
    block = re.search(r"```python\n(.*?)```", section, re.S)
    assert block is not None
    code = block.group(1)
    # The guide shows the example file's code as it is.
    assert code in (ROOT / "examples" / "first_skill.py").read_text()
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=110, cwd=ROOT
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "outcome: succeeded - goal reached" in result.stdout
    assert "pr2: driving living-room -> dining-room" in result.stdout
