"""``python -m smach.introspection`` and ``plan-bridge view/export``."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest
from viewer_machines import demo_machine

from smach.introspection.journal import Journal


@pytest.fixture
def journal(tmp_path: Path) -> Path:
    sm, hold = demo_machine()
    path = tmp_path / "run.jsonl"
    with Journal(path, sm, header={"title": "demo"}):
        hold["pick"].release("picked")
        hold["arm"].release("done")
        hold["base"].go.set()
        sm.execute()
    return path


def smach_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "smach.introspection", *args],
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("fmt", "start"), [("dot", "digraph"), ("mermaid", "stateDiagram-v2"), ("svg", "<svg")]
)
def test_export_writes_each_format_to_stdout(journal: Path, fmt: str, start: str) -> None:
    done = smach_cli("export", str(journal), "--format", fmt, "--event", "12")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(start)


@pytest.mark.timeout(60)
def test_export_to_a_file_at_a_time(journal: Path, tmp_path: Path) -> None:
    out = tmp_path / "at.svg"
    done = smach_cli("export", str(journal), "--format", "svg", "--at", "0", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert out.read_text().startswith("<svg") and "wrote" in done.stderr


@pytest.mark.timeout(60)
def test_bad_input_exits_2_with_one_line(tmp_path: Path, journal: Path) -> None:
    done = smach_cli("export", str(tmp_path / "missing.jsonl"), "--format", "dot")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "missing.jsonl" in done.stderr
    broken = tmp_path / "broken.jsonl"
    broken.write_text('{"kind": "header"}\nnot json\n')
    done = smach_cli("export", str(broken), "--format", "svg")
    assert done.returncode == 2 and "not a JSON line" in done.stderr
    done = smach_cli("export", str(journal), "--format", "png")
    assert done.returncode == 2
    done = smach_cli("export", str(journal), "--format", "svg", "--at", "1", "--event", "2")
    assert done.returncode == 2


@pytest.mark.timeout(60)
def test_view_serves_the_journal_on_loopback(journal: Path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "smach.introspection", "view", str(journal)],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        match = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
        assert match, line
        with urllib.request.urlopen(f"{match.group(0)}api/info", timeout=10) as response:
            info = json.load(response)
        assert info["live"] is False and info["title"] == "demo"
    finally:
        proc.terminate()
        proc.wait(10)
        if proc.stderr is not None:
            proc.stderr.close()


@pytest.mark.timeout(60)
def test_plan_bridge_view_export_and_export_commands(
    journal: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from plan_bridge import cli

    assert cli.main(["view", str(journal), "--export", "mermaid", "--event", "5"]) == 0
    assert capsys.readouterr().out.startswith("stateDiagram-v2")
    out = tmp_path / "run.svg"
    assert cli.main(["export", str(journal), "--format", "svg", "-o", str(out)]) == 0
    assert out.read_text().startswith("<svg")
    assert cli.main(["view", str(journal), "--at", "1"]) == 2
    assert "--export" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["view", "run.jsonl", "--port", "http"], "--port: expected a port number, got 'http'"),
        (["view", "run.jsonl", "--port", "70000"], "expected a port number 0..65535, got '70000'"),
        (["ros", "srv", "--timeout", "soon"], "--timeout: expected seconds (a number), got 'soon'"),
        (["export", "r", "--format", "dot", "--at", "-1"], "a number of seconds >= 0, got '-1'"),
        (["export", "r", "--format", "dot", "--at", "inf"], "a number of seconds >= 0, got 'inf'"),
        (["export", "r", "--format", "dot", "--event", "2.5"], "a whole number, got '2.5'"),
        (["export", "r", "--format", "dot", "--event", "-3"], "a number >= 0, got '-3'"),
    ],
)
def test_a_bad_number_is_refused_with_what_was_expected(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from smach.introspection import cli

    with pytest.raises(SystemExit) as stop:
        cli.main(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


def test_view_on_a_port_in_use_exits_2_and_says_where(
    journal: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import socket

    from smach.introspection import cli

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert cli.main(["view", str(journal), "--port", str(port)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"smach-viewer: error: cannot listen on 127.0.0.1:{port}: ")
    assert err.count("\n") == 1
