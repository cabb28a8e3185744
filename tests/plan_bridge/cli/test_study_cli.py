"""`plan-bridge study`: --cluster, --resume, and a local study that never loads Dask."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from plan_bridge.cli import main

ROOMS = str(Path(__file__).parents[1] / "data" / "rooms")
SMALL = [ROOMS, "--runs", "2", "--fault-rates", "0,0.5", "--approaches", "planned,no-replan"]


def test_a_bad_cluster_address_is_refused_with_what_is_allowed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["study", *SMALL, "--out", str(tmp_path), "--cluster", "10.0.0.1:8786"])
    assert code == 2
    err = capsys.readouterr().err
    assert "tcp://HOST:PORT" in err and "local:N" in err
    assert not (tmp_path / "results.csv").exists()


def test_jobs_and_cluster_together_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["study", *SMALL, "--out", str(tmp_path), "--cluster", "local:2", "--jobs", "2"])
    assert code == 2
    assert "--jobs is for local runs" in capsys.readouterr().err


@pytest.mark.timeout(300)
def test_a_study_on_a_local_cluster_writes_the_report_and_resume_is_explicit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("distributed")
    out = tmp_path / "study"
    assert main(["study", *SMALL, "--out", str(out), "--cluster", "local:2"]) == 0
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 8 and all(r["worker"].startswith("tcp://127.0.0.1:") for r in rows)
    assert "Dask cluster local:2" in capsys.readouterr().err
    assert "dask local:2" in (out / "report.md").read_text()
    # The same --out again without --resume would mix two studies: refused.
    assert main(["study", *SMALL, "--out", str(out)]) == 2
    assert "pass --resume" in capsys.readouterr().err
    # --resume with one more seed runs only that seed, locally this time.
    more = [ROOMS, "--runs", "3", "--fault-rates", "0,0.5", "--approaches", "planned,no-replan"]
    assert main(["study", *more, "--out", str(out), "--resume", "--jobs", "1"]) == 0
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    keys = [(r["approach"], r["fault_rate"], r["seed"]) for r in rows]
    assert len(keys) == len(set(keys)) == 12


@pytest.mark.timeout(300)
def test_a_local_study_never_imports_dask(tmp_path: Path) -> None:
    script = (
        "import sys\n"
        "from plan_bridge.cli import main\n"
        f"code = main(['study', *{SMALL!r}, '--runs', '1', '--out', {str(tmp_path)!r}])\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed'))\n"
        "print('LOADED', loaded)\n"
        "sys.exit(code)\n"
    )
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=240, env=env
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "LOADED []" in done.stdout
    assert (tmp_path / "report.md").exists()


@pytest.mark.timeout(300)
def test_a_terminated_study_keeps_its_rows_and_says_how_to_continue(tmp_path: Path) -> None:
    out = tmp_path / "study"
    args = [ROOMS, "--runs", "30", "--fault-rates", "0,0.5", "--approaches", "planned"]
    command = [sys.executable, "-m", "plan_bridge", "study", *args, "--out", str(out)]
    process = subprocess.Popen(
        [*command, "--jobs", "1"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    results = out / "results.csv"
    while process.poll() is None and (not results.exists() or results.read_text().count("\n") < 3):
        time.sleep(0.01)
    process.terminate()
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143, err
    lines = err.strip().splitlines()
    assert lines[-1] == "plan-bridge: terminated"
    assert "the same command with --resume runs the rest" in lines[-2]
    with results.open() as f:
        kept = len(list(csv.DictReader(f)))
    assert f"stopped with {kept} of 60 runs" in lines[-2]

    resumed = subprocess.run([*command, "--resume"], capture_output=True, text=True, timeout=240)
    assert resumed.returncode == 0, resumed.stderr
    with results.open() as f:
        keys = [(r["fault_rate"], r["seed"]) for r in csv.DictReader(f)]
    assert len(keys) == len(set(keys)) == 60
