"""Another revision of this repository beside the working one, for benchmarks that
compare with it in the same run: a temporary git worktree whose ``src`` a fresh
process imports instead (``PYTHONPATH``), with this environment's packages."""

from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


class Worktree:
    """``with Worktree(rev) as path:`` a checkout of ``rev`` (None: no checkout, None)."""

    def __init__(self, rev: str | None) -> None:
        self.rev = rev
        self.path: Path | None = None

    def __enter__(self) -> Path | None:
        if self.rev is None:
            return None
        self.path = Path(tempfile.mkdtemp(prefix="bench-revision-"))
        subprocess.run(
            ["git", "worktree", "add", "--detach", str(self.path), self.rev],
            cwd=ROOT,
            check=True,
            capture_output=True,
        )
        return self.path

    def __exit__(self, *exc: object) -> None:
        if self.path is not None:
            subprocess.run(
                ["git", "worktree", "remove", "--force", str(self.path)],
                cwd=ROOT,
                check=False,
                capture_output=True,
            )
