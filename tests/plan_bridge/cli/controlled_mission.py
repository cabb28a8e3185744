"""`plan-bridge run ... --control` in a subprocess, for the tests of `plan-bridge control`."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import threading
import time
from typing import Any

import pytest

from plan_bridge.cli import main


class ControlledMission:
    """`plan-bridge run ARGS` in a subprocess (ARGS hold `--control`); the control URL
    read from its stderr."""

    def __init__(self, *args: str) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "plan_bridge", "run", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.url = ""
        found = threading.Event()
        self.ended = threading.Event()
        self.stderr: list[str] = []

        def read() -> None:
            assert self.process.stderr is not None
            for line in self.process.stderr:
                self.stderr.append(line)
                if "the mission ended" in line:  # the viewer serves on until Ctrl-C
                    self.ended.set()
                match = re.match(r"control: (http://\S+)", line)
                if match:
                    self.url = match.group(1)
                    found.set()

        self.reader = threading.Thread(target=read, daemon=True)
        self.reader.start()
        self.stdout = ""
        if not found.wait(60):
            self.finish()
            raise AssertionError("no control URL printed: " + "".join(self.stderr))

    def finish(self) -> int:
        """Wait for the mission (Ctrl-C its viewer once it ended; kill it after 120 s).

        Closes its pipes and returns its exit code (130 when the Ctrl-C came before the
        viewer waited for it: the tests read the outcome from --json instead).
        """
        deadline = time.monotonic() + 120
        while self.process.poll() is None and not self.ended.is_set():
            if time.monotonic() > deadline:
                break
            self.ended.wait(0.1)
        if self.process.poll() is None and self.ended.is_set():
            self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(max(1.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)
        assert self.process.stdout is not None and self.process.stderr is not None
        self.stdout = self.process.stdout.read()
        self.process.stdout.close()
        self.reader.join(10)
        self.process.stderr.close()
        return self.process.returncode

    def figures(self) -> dict[str, Any]:
        """The run's --json line (after :meth:`finish`)."""
        return dict(json.loads(self.stdout.strip().splitlines()[-1]))

    def end(self) -> None:
        """After a test: kill the mission if it still runs, and close its pipes."""
        if self.process.poll() is None:
            self.process.kill()
        if not self.process.stdout or not self.process.stdout.closed:
            self.finish()


def control(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """`plan-bridge control ARGS` in this process: exit code, stdout, stderr."""
    code = main(["control", *args])
    out, err = capsys.readouterr()
    return code, out, err
