"""Our ``check`` verdict against unified-planning's own reader on the IPC corpus.

The corpus (``../shared/pddl-corpus`` next to the repository, or the folder named by
``PLAN_BRIDGE_IPC_CORPUS``) holds one domain and its first problem for every IPC
domain variant 1998-2014: ``ipc-YYYY/NAME/domain.pddl`` and ``problem.pddl``. The
files are read where they are, never copied into the project.

Each pair is judged in a worker process with a time limit (a pair that hangs is
killed and reported, the worker restarted), two ways:

* ``full``: unified-planning's reader alone on the user's files, and our verdict as
  ``plan-bridge check`` reaches it without planning: the front end
  (:func:`~plan_bridge.cli.base.check_input`), then UP's reader on the rewritten text
  (:func:`~plan_bridge.pddl.task.load_task`);
* ``front-end``: the front end alone, and UP's reader alone only on the pairs the front
  end refuses (to show that UP refuses them too): a few seconds for the whole corpus.

Used by ``test_ipc_corpus_agreement.py`` and ``tools/ipc_corpus_agreement.py``.
"""

from __future__ import annotations

import json
import os
import queue
import select
import subprocess
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[3]
IPC_CORPUS = Path(
    os.environ.get("PLAN_BRIDGE_IPC_CORPUS", REPO.parent / "shared" / "pddl-corpus")
).resolve()

#: UP's reader answers.
READS, REFUSES = "reads", "refuses"
#: Our answers.
ACCEPTS, ERROR, UNSUPPORTED = "accepts", "error", "unsupported"
#: Either side, when the pair did not end well.
TIMEOUT, CRASHED = "timeout", "crashed"


@dataclass(frozen=True)
class Pair:
    name: str
    """``ipc-YYYY/NAME``."""
    domain: Path
    problem: Path


@dataclass(frozen=True)
class Verdict:
    pair: Pair
    up: str
    """:data:`READS`, :data:`REFUSES`, :data:`TIMEOUT`, :data:`CRASHED` or ``""`` (not asked)."""
    ours: str
    """:data:`ACCEPTS`, :data:`ERROR`, :data:`UNSUPPORTED`, :data:`TIMEOUT` or :data:`CRASHED`."""
    up_message: str = ""
    message: str = ""
    """Our refusal (its first line), or the traceback of a crash."""
    line: int | None = None
    """The line our refusal names."""
    warnings: tuple[str, ...] = ()
    """The first line of each of our warnings."""
    seconds: float = 0.0
    up_seconds: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)


def ipc_pairs(root: Path = IPC_CORPUS) -> list[Pair]:
    """Every (domain, problem) pair of the corpus, in name order."""
    if not root.is_dir():
        return []
    return [
        Pair(
            f"{domain.parent.parent.name}/{domain.parent.name}",
            domain,
            domain.parent / "problem.pddl",
        )
        for domain in sorted(root.glob("ipc-*/*/domain.pddl"))
    ]


# -- in the worker -------------------------------------------------------------------


def _up_alone(pair: Pair) -> tuple[str, str, float]:
    from unified_planning.io import PDDLReader

    started = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            PDDLReader().parse_problem(str(pair.domain), str(pair.problem))
    except Exception as exc:  # UP refuses with many exception types
        first = (str(exc).strip().splitlines() or [""])[0]
        return REFUSES, f"{type(exc).__name__}: {first}"[:300], time.perf_counter() - started
    return READS, "", time.perf_counter() - started


def _ours(pair: Pair, mode: str) -> dict[str, Any]:
    from plan_bridge.cli.base import check_input
    from plan_bridge.errors import PddlError, UnsupportedFeatureError
    from plan_bridge.pddl.task import load_task

    started = time.perf_counter()
    found: dict[str, Any] = {"ours": ACCEPTS, "message": "", "line": None, "warnings": ()}
    try:
        warned = list(check_input(pair.domain, pair.problem))
        if mode == "full":
            load_task(pair.domain, pair.problem)
        found["warnings"] = tuple(w.splitlines()[0] for w in warned)
    except UnsupportedFeatureError as exc:
        found.update(ours=UNSUPPORTED, message=str(exc).splitlines()[0], line=exc.line)
    except PddlError as exc:
        found.update(ours=ERROR, message=str(exc).splitlines()[0], line=exc.line)
    except BaseException as exc:
        found.update(ours=CRASHED, message="".join(traceback.format_exception(exc))[-2000:])
    found["seconds"] = time.perf_counter() - started
    return found


def _judge(pair: Pair, mode: str) -> dict[str, Any]:
    found = _ours(pair, mode)
    if mode == "full" or found["ours"] != ACCEPTS:
        up, up_message, up_seconds = _up_alone(pair)
        found.update(up=up, up_message=up_message, up_seconds=up_seconds)
    return found


def _serve(mode: str) -> None:
    """The worker's loop: a pair per line on stdin, its findings as a JSON line on
    stdout (anything else printed goes to stderr)."""
    import plan_bridge.cli.base  # noqa: F401  (imported before any clock starts)

    if mode == "full":
        import unified_planning.io  # noqa: F401
    answers = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    answers.write("ready\n")
    answers.flush()
    for row in sys.stdin:
        name, domain, problem = json.loads(row)
        answers.write(json.dumps(_judge(Pair(name, Path(domain), Path(problem)), mode)) + "\n")
        answers.flush()


# -- in the caller -------------------------------------------------------------------


class _Worker:
    """A Python process running :func:`_serve` (this file as a script)."""

    def __init__(self, mode: str) -> None:
        self.process = subprocess.Popen(
            [sys.executable, __file__, "--serve", mode],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        if self._answer(120) != "ready":
            self.stop()
            raise RuntimeError("the corpus worker did not start within 120 s")

    def _answer(self, limit: float) -> str | None:
        assert self.process.stdout is not None
        readable, _, _ = select.select([self.process.stdout], [], [], limit)
        if not readable:
            return None
        return self.process.stdout.readline().strip()

    def judge(self, pair: Pair, limit: float) -> dict[str, Any] | None:
        """The worker's findings, or ``None`` when it took longer than ``limit``."""
        assert self.process.stdin is not None
        try:
            self.process.stdin.write(json.dumps([pair.name, str(pair.domain), str(pair.problem)]))
            self.process.stdin.write("\n")
            self.process.stdin.flush()
            answer = self._answer(limit)
        except OSError:
            answer = ""
        if answer is None:
            return None
        if not answer:
            return {"ours": CRASHED, "message": "the worker process died"}
        found: dict[str, Any] = json.loads(answer)
        return found

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(10)
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                stream.close()


def judge_pairs(
    pairs: Iterable[Pair], *, mode: str = "full", limit: float = 120.0, jobs: int = 1
) -> Iterator[Verdict]:
    """A :class:`Verdict` per pair (in the order they finish), ``jobs`` pairs at once,
    each within ``limit`` seconds (a worker that takes longer is killed and restarted,
    and the pair reported as :data:`TIMEOUT`)."""
    pending: queue.Queue[Pair | None] = queue.Queue()
    done: queue.Queue[Verdict | BaseException] = queue.Queue()
    count = 0
    for pair in pairs:
        pending.put(pair)
        count += 1
    jobs = max(1, min(jobs, count))
    for _ in range(jobs):
        pending.put(None)

    def work() -> None:
        worker: _Worker | None = None
        try:
            while (pair := pending.get()) is not None:
                if worker is None:
                    worker = _Worker(mode)
                started = time.perf_counter()
                found = worker.judge(pair, limit)
                if found is None or worker.process.poll() is not None:
                    worker.stop()  # a hang is killed, a dead worker replaced
                    worker = None
                if found is None:
                    found = {"ours": TIMEOUT, "message": f"no verdict within {limit:g} s"}
                found.setdefault("seconds", time.perf_counter() - started)
                done.put(_verdict(pair, found))
        except BaseException as exc:
            done.put(exc)
        finally:
            if worker is not None:
                worker.stop()

    threads = [threading.Thread(target=work, daemon=True) for _ in range(jobs)]
    for thread in threads:
        thread.start()
    for _ in range(count):
        item = done.get()
        if isinstance(item, BaseException):
            raise item
        yield item
    for thread in threads:
        thread.join()


def _verdict(pair: Pair, found: dict[str, Any]) -> Verdict:
    return Verdict(
        pair,
        up=found.get("up", ""),
        ours=found["ours"],
        up_message=found.get("up_message", ""),
        message=found.get("message", ""),
        line=found.get("line"),
        warnings=tuple(found.get("warnings", ())),
        seconds=found.get("seconds", 0.0),
        up_seconds=found.get("up_seconds", 0.0),
    )


def disagreements(verdicts: Iterable[Verdict]) -> list[str]:
    """One line per pair that breaks the rules: no traceback, no hang, and no pair UP's
    reader reads (or, in ``front-end`` mode, that it would read) refused by us."""
    problems = []
    for verdict in verdicts:
        if verdict.ours in (TIMEOUT, CRASHED):
            problems.append(f"{verdict.pair.name}: {verdict.ours}: {verdict.message}")
        elif verdict.up == READS and verdict.ours != ACCEPTS:
            problems.append(
                f"{verdict.pair.name}: unified-planning reads it, we refuse it: {verdict.message}"
            )
        elif verdict.ours in (ERROR, UNSUPPORTED) and verdict.up in (TIMEOUT, CRASHED, ""):
            problems.append(f"{verdict.pair.name}: no answer from unified-planning's reader")
    return problems


if __name__ == "__main__" and sys.argv[1:2] == ["--serve"]:
    _serve(sys.argv[2])
