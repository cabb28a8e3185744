"""`./dev`'s first set-up says what pip is doing: a line when pip's latest line changes
(looked at every 5 s), not the same line again every 5 s (a first `./dev run` printed
"Installing collected packages" 16 times). Its `watch_pip` runs against a fake pip
that writes a log slowly; nothing is installed.

`./dev test` lints, type-checks, then runs pytest on xdist workers: everything with
coverage (and records the durations file), `--fast` the unit tier, or what it is given.
Checked against a fake installed `.venv` that logs each call. Its coverage counts the
programs the tests start (pyproject.toml's [tool.coverage.run]): checked for real, on a
`python -m plan_bridge --help` started by a test."""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def watch(tmp_path: Path, script: str) -> list[str]:
    """The lines `watch_pip` prints while a fake pip runs ``script`` (bash) on its log."""
    dev = (ROOT / "dev").read_text()
    function = re.search(r"^watch_pip\(\) \{\n.*?^\}\n", dev, re.S | re.M)
    assert function is not None, "dev has no watch_pip function"
    log = tmp_path / "install.log"
    log.write_text("")
    program = (
        "set -euo pipefail\n"
        + function.group(0)
        + f"( {script} ) >>{log} &\n"
        + f"watch_pip $! {log}\n"
    )
    done = subprocess.run(
        ["bash", "-c", program], capture_output=True, text=True, timeout=60, check=True
    )
    return done.stderr.splitlines()


@pytest.mark.timeout(60)
def test_dev_prints_what_pip_does_only_when_it_changes(tmp_path: Path) -> None:
    lines = watch(
        tmp_path,
        "echo 'Collecting unified-planning'; sleep 7; "
        "echo 'Installing collected packages: unified-planning, smach-planner'; sleep 9",
    )
    assert lines == [
        "[dev] 5s: Collecting unified-planning",
        "[dev] 10s: Installing collected packages: unified-planning, smach-planner",
    ]  # not again at 15 s


def fake_dev(tmp_path: Path) -> tuple[Path, dict[str, str]]:
    """A copy of ``./dev`` beside a fake, already installed ``.venv`` whose python,
    ruff and mypy only log how they were called (to calls.log), and an environment
    where chromium and graphviz are found (nothing is installed)."""
    (tmp_path / "dev").write_text((ROOT / "dev").read_text())
    (tmp_path / "dev").chmod(0o755)
    (tmp_path / "pyproject.toml").write_text("[project]\nname = 'fake'\n")
    stamp = hashlib.sha1((tmp_path / "pyproject.toml").read_bytes()).hexdigest()[:12]
    bin_dir = tmp_path / ".venv" / "bin"
    bin_dir.mkdir(parents=True)
    (tmp_path / ".venv" / f".installed-{stamp}").write_text("")
    tools = tmp_path / "tools-on-path"
    tools.mkdir()
    for folder, names in ((bin_dir, ("python", "ruff", "mypy")), (tools, ("chromium", "dot"))):
        for name in names:
            script = folder / name
            script.write_text(f'#!/bin/sh\necho "{name} $*" >> "{tmp_path}/calls.log"\n')
            script.chmod(0o755)
    env = {k: v for k, v in os.environ.items() if not k.startswith("COVERAGE_")}
    env.update(PATH=f"{tools}:{os.environ['PATH']}", DEV_TEST_WORKERS="3")
    return tmp_path / "dev", env


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("args", "pytest_args"),
    [
        (
            [],
            "-m pytest -n 3 --dist loadgroup --durations=15 --store-durations"
            " --cov=smach --cov=plan_bridge --cov-report=term:skip-covered",
        ),
        (["--fast"], "-m pytest -n 3 --dist loadgroup -m unit --durations=5"),
        (["--fast", "-x"], "-m pytest -n 3 --dist loadgroup -m unit --durations=5 -x"),
        (["-m", "mission"], "-m pytest -n 3 --dist loadgroup --durations=15 -m mission"),
    ],
)
def test_dev_test_lints_then_runs_the_tier_asked_for(
    tmp_path: Path, args: list[str], pytest_args: str
) -> None:
    """`./dev test` runs everything with coverage and records durations; `--fast` the
    unit tier; other arguments go to pytest. ruff and mypy run first every time."""
    dev, env = fake_dev(tmp_path)
    done = subprocess.run(
        [str(dev), "test", *args], capture_output=True, text=True, env=env, timeout=50
    )
    assert done.returncode == 0, done.stderr
    calls = (tmp_path / "calls.log").read_text().splitlines()
    assert calls == [
        "ruff check src tests benchmarks examples tools",
        "ruff format --check src tests benchmarks examples tools",
        "mypy ",
        f"python {pytest_args}",
    ]


@pytest.mark.timeout(60)
def test_dev_test_combines_coverage_data_written_after_the_report(tmp_path: Path) -> None:
    """A program that outlived its test writes its coverage data after pytest-cov
    combined it: `./dev test` combines that file into .coverage and removes what
    coverage could not read, then exits with pytest's status."""
    dev, env = fake_dev(tmp_path)
    python = tmp_path / ".venv" / "bin" / "python"
    python.write_text(
        python.read_text() + 'case "$*" in *--cov=*) touch .coverage.vm.pid1.late; exit 3 ;; esac\n'
    )
    done = subprocess.run([str(dev), "test"], capture_output=True, text=True, env=env, timeout=50)
    assert done.returncode == 3, done.stderr  # pytest's
    calls = (tmp_path / "calls.log").read_text().splitlines()
    assert calls[-2:] == [
        "python -m coverage combine --append --quiet .",
        "python -m coverage report --format=total --ignore-errors",
    ]
    # The fake coverage combined nothing: the file it could not read is gone all the same.
    assert "could not be read: .coverage.vm.pid1.late" in done.stderr
    assert "1 coverage data file(s) came after the report, combined into .coverage" in done.stderr
    assert not list(tmp_path.glob(".coverage*"))


CHILD_TEST = """
import subprocess
import sys


def test_help() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "plan_bridge", "--help"], capture_output=True, text=True
    )
    assert done.returncode == 0 and "plan" in done.stdout
"""


def measured_lines(tmp_path: Path, config: Path) -> tuple[set[int], list[str]]:
    """Run, under pytest with ``--cov=plan_bridge`` and the coverage ``config``, a test
    that only starts `python -m plan_bridge --help` (the test imports no plan_bridge
    itself); the lines of plan_bridge/cli/__init__.py the combined data holds, and the
    files left beside it."""
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "test_child.py").write_text(CHILD_TEST)
    data = tmp_path / "data" / ".coverage"
    data.parent.mkdir()
    # As in a run of its own: no coverage of this run's passes to it.
    env = {k: v for k, v in os.environ.items() if not k.startswith("COVERAGE_")}
    env["COVERAGE_FILE"] = str(data)
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist", "-q",
         "--rootdir", str(tmp_path), "-c", str(config), "--cov=plan_bridge",
         f"--cov-config={config}", "--cov-report=", str(tmp_path / "test_child.py")],
        capture_output=True, text=True, cwd=tmp_path, env=env, timeout=100,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    from coverage import CoverageData

    combined = CoverageData(str(data))
    combined.read()
    cli = str(ROOT / "src" / "plan_bridge" / "cli" / "__init__.py")
    left = sorted(p.name for p in data.parent.iterdir() if p != data)
    return set(combined.lines(cli) or ()), left


@pytest.mark.timeout(120)
def test_coverage_counts_the_programs_a_test_starts(tmp_path: Path) -> None:
    """`./dev test` measures coverage with pyproject.toml's [tool.coverage.run]: a
    `python -m plan_bridge` a test starts is measured too, its data combined with the
    rest and no data file left behind. Without those settings it is not measured."""
    lines, left = measured_lines(tmp_path / "with", ROOT / "pyproject.toml")
    assert len(lines) > 10, lines  # main() ran, in the child process
    assert left == []
    plain = tmp_path / "without" / "pytest.ini"
    plain.parent.mkdir()
    plain.write_text("[pytest]\n")
    lines, left = measured_lines(tmp_path / "without", plain)
    assert lines == set() and left == []
