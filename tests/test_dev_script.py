"""`./dev`'s first set-up says what pip is doing: a line when pip's latest line changes
(looked at every 5 s), not the same line again every 5 s (a first `./dev run` printed
"Installing collected packages" 16 times). Its `watch_pip` runs against a fake pip
that writes a log slowly; nothing is installed.

`./dev test` lints, type-checks, then runs pytest on xdist workers: everything with
coverage (and records the durations file), `--fast` the unit tier, or what it is given.
Checked against a fake installed `.venv` that logs each call."""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
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
    env = dict(os.environ, PATH=f"{tools}:{os.environ['PATH']}", DEV_TEST_WORKERS="3")
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
