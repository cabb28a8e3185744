"""The plan-bridge command line: output, exit codes, speed of help and errors."""

from __future__ import annotations

import json
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from plan_bridge.cli import commands, main

DOMAINS = Path(__file__).resolve().parents[3] / "domains"

SCRIPT = Path(sys.executable).with_name("plan-bridge")


def _cpu_of_children() -> float:
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def _run(*args: str) -> tuple[subprocess.CompletedProcess[str], float]:
    """The program's result and the CPU seconds it used: the work it did, which a busy
    machine does not stretch as it does the time it took (about 0.2 s for --help; twice
    that measured by coverage, docs/testing.md)."""
    before = _cpu_of_children()
    completed = subprocess.run(
        [str(SCRIPT), *args], capture_output=True, text=True, timeout=60, check=False
    )
    return completed, _cpu_of_children() - before


def test_every_subcommand_is_in_the_table() -> None:
    assert set(commands()) == {
        "run",
        "check",
        "problem",
        "import",
        "control",
        "plan",
        "skills",
        "view",
        "export",
        "study",
    }


def test_subcommand_modules_do_not_import_the_cli_table_back() -> None:
    import ast
    import importlib.util

    from plan_bridge.cli import MODULES

    for module in MODULES:
        spec = importlib.util.find_spec(module)
        assert spec is not None and spec.origin is not None
        tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
        imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)} | {
            alias.name
            for node in ast.walk(tree)
            if isinstance(node, ast.Import)
            for alias in node.names
        }
        assert "plan_bridge.cli" not in imported, module


@pytest.mark.skipif(not SCRIPT.exists(), reason="console script not installed")
def test_help_answers_fast_and_lists_plan() -> None:
    completed, cpu = _run("--help")
    assert completed.returncode == 0
    assert "plan" in completed.stdout
    assert cpu < 1.0, cpu  # the planners are not imported


@pytest.mark.skipif(not SCRIPT.exists(), reason="console script not installed")
def test_missing_file_is_a_fast_bad_input_error(tmp_path: Path) -> None:
    completed, cpu = _run("plan", str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl"))
    assert completed.returncode == 2
    assert "domain file not found" in completed.stderr
    assert "Traceback" not in completed.stderr
    assert cpu < 1.5, cpu


@pytest.mark.skipif(not SCRIPT.exists(), reason="console script not installed")
def test_solved_plan_prints_numbered_steps_end_to_end(bench: Path) -> None:
    folder = bench / "gripper"
    completed, _ = _run("plan", str(folder / "domain.pddl"), str(folder / "prob01.pddl"))
    assert completed.returncode == 0, completed.stderr
    lines = completed.stdout.splitlines()
    assert lines[0] == " 1. (pick ball1 rooma left)"
    assert lines[-1].startswith("solved: 11 actions in ")
    assert "planning with fast-downward (timeout 60 s)..." in completed.stderr


def test_json_output_is_one_object(bench: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = bench / "blocks"
    code = main(
        [
            "plan",
            str(folder / "domain.pddl"),
            str(folder / "probBLOCKS-4-0.pddl"),
            "--json",
            "--planner",
            "pyperplan",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    payload = json.loads(out)
    assert payload["status"] == "solved" and payload["planner"] == "pyperplan"
    assert payload["plan"][0].startswith("(") and len(payload["plan"]) == payload["plan_length"]
    assert payload["planning_time_s"] > 0 and payload["explanation"] == ""


def test_unsolvable_problem_exits_1_with_explanation(
    doors,
    capsys: pytest.CaptureFixture[str],  # type: ignore[no-untyped-def]
) -> None:
    domain, problem = doors(extra="")
    assert main(["plan", str(domain), str(problem), "--json"]) == 1
    payload = json.loads(capsys.readouterr().out)
    assert payload["status"] == "unsolvable"
    assert payload["unreachable_goals"] == ["(at vault)"]
    assert "(at vault)" in payload["explanation"]


@pytest.mark.timeout(30)
def test_timeout_exits_1(bench: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = bench / "blocks"
    code = main(
        [
            "plan",
            str(folder / "domain.pddl"),
            str(folder / "probBLOCKS-14-0.pddl"),
            "--planner",
            "pyperplan",
            "--timeout",
            "0.5",
        ]
    )
    assert code == 1
    assert capsys.readouterr().out.startswith("timeout: no plan after")


def test_storage_is_a_bad_input_error(bench: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = bench / "storage"
    assert main(["plan", str(folder / "domain.pddl"), str(folder / "p01.pddl")]) == 2
    err = capsys.readouterr().err
    assert f"{folder / 'domain.pddl'}:12:16: unsupported PDDL construct" in err


def test_unknown_planner_is_a_bad_input_error(
    doors,
    capsys: pytest.CaptureFixture[str],  # type: ignore[no-untyped-def]
) -> None:
    domain, problem = doors()
    assert main(["plan", str(domain), str(problem), "--planner", "nope"]) == 2
    err = capsys.readouterr().err
    assert "unknown planner 'nope'" in err and "fast-downward" in err
    assert "use auto" in err and "warm-gbfs" in err  # the names that are not engines too


@pytest.mark.parametrize("value", ["0", "-1", "soon", "nan"])
def test_bad_timeout_is_a_usage_error(
    doors,
    value: str,
    capsys: pytest.CaptureFixture[str],  # type: ignore[no-untyped-def]
) -> None:
    domain, problem = doors()
    with pytest.raises(SystemExit) as caught:
        main(["plan", str(domain), str(problem), "--timeout", value])
    assert caught.value.code == 2
    assert "--timeout" in capsys.readouterr().err


@pytest.mark.timeout(120)
def test_run_with_ros_but_without_rclpy_says_which_extra_to_install() -> None:
    # A process in which rclpy cannot be imported (as without the ros extra).
    code = (
        "import sys; sys.modules['rclpy'] = None\n"
        "from plan_bridge.cli import main\n"
        f"sys.exit(main(['run', {str(DOMAINS / 'fetch_drink')!r}, '--ros', '--quiet']))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=100, check=False
    )
    assert proc.returncode == 2, proc.stderr
    assert 'pip install "smach-planner[ros]"' in proc.stderr
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
