"""What a study ran on: package and planner versions, CPU model and count, per machine.

A study appends one *session* (the machine that wrote the rows and, on a cluster,
every worker's machine) to ``environment.json`` in its output folder each time it
runs, so a resumed study reports every machine that contributed rows. Versions are
read from package metadata: nothing here imports a planner or Dask.
"""

from __future__ import annotations

import functools
import json
import os
import platform
import socket
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any

__all__ = [
    "PACKAGES",
    "PLANNER_PACKAGES",
    "cpu_model",
    "machine_info",
    "read_sessions",
    "record_session",
    "source_revision",
]

#: Distributions whose versions the report records.
PACKAGES = (
    "smach-planner",
    "unified-planning",
    "up-fast-downward",
    "up-pyperplan",
    "pyperplan",
    "up-kairos",
    "up-tamer",
    "matplotlib",
    "dask",
    "distributed",
)
#: The packages that carry each planner engine of the study.
PLANNER_PACKAGES = {
    "fast-downward": ("up-fast-downward",),
    "pyperplan": ("up-pyperplan", "pyperplan"),
    "kairos": ("up-kairos",),
    "tamer": ("up-tamer",),
}


def _version(name: str) -> str:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return ""


@functools.lru_cache(maxsize=1)
def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else what ``platform`` knows)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def source_revision(folder: Path | None = None) -> str:
    """The git commit of the plan_bridge source in use, ``+dirty`` if the code has
    local edits (tracked files under ``src/`` or ``domains/``: a study rewriting its
    own report in the checkout does not count).

    Empty when plan_bridge is not run from a git checkout (an installed wheel).
    """
    folder = folder or Path(__file__).resolve().parent
    try:
        head = subprocess.run(
            ["git", "-C", str(folder), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            [
                *("git", "-C", str(folder), "status", "--porcelain", "--untracked-files=no"),
                *("--", ":/src", ":/domains"),
            ],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return head + ("+dirty" if dirty else "")


def machine_info() -> dict[str, Any]:
    """This process's machine: host, CPU, OS, Python and package versions."""
    return {
        "host": socket.gethostname(),
        "cpu_model": cpu_model(),
        "cpu_count": os.cpu_count() or 0,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "packages": {name: v for name in PACKAGES if (v := _version(name))},
    }


def record_session(out: Path, *, executor: str, workers: dict[str, dict[str, Any]]) -> None:
    """Append this session (the writing machine plus each worker's) to ``environment.json``."""
    path = out / "environment.json"
    sessions = read_sessions(out)
    sessions.append(
        {
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "executor": executor,
            "argv": sys.argv[1:],
            "writer": machine_info(),
            "source": source_revision(),
            "workers": workers,
        }
    )
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps({"sessions": sessions}, indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def read_sessions(out: Path) -> list[dict[str, Any]]:
    path = out / "environment.json"
    if not path.exists():
        return []
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(
            f"{path}: not valid JSON ({exc}); delete it to start a new record"
        ) from exc
    sessions = data.get("sessions", []) if isinstance(data, dict) else []
    return [s for s in sessions if isinstance(s, dict)]
