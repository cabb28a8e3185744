"""Smoke test of benchmarks/scale.py: two small buildings, each phase measured.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "scale.py"


def _bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("scale_bench", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up)
    spec.loader.exec_module(module)
    return module


def test_a_size_is_rooms_robots_and_deliveries() -> None:
    size = _bench().Size.parse("25x4x4")
    assert (size.rooms, size.robots, size.deliveries) == (25, 4, 4) and str(size) == "25x4x4"
    with pytest.raises(Exception, match="ROOMSxROBOTSxDELIVERIES"):
        _bench().Size.parse("25x4")


@pytest.mark.timeout(300)
def test_quick_run_reports_every_phase_per_size(tmp_path: Path) -> None:
    out = tmp_path / "scale.json"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=280,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert "| rooms x robots x deliveries | run | goal | load | task | 1st plan |" in proc.stdout
    result = json.loads(out.read_text())
    assert [row["size"] for row in result["rows"]] == ["4x1x1", "9x2x2"]
    for row in result["rows"]:
        assert row["outcome"] == "succeeded"
        assert row["load_s"] > 0 and row["first_plan_s"] > 0 and row["wall_s"] > row["total_s"]
