"""Planner worker processes: a hard wall-clock limit for every engine.

Each solve runs in a separate, killable process, because some engines ignore
UP's ``timeout`` (pyperplan) and because up-fast-downward writes ``output.sas``
into the current directory (so every solve gets its own working directory).

Why a plain subprocess speaking JSON lines, not ``multiprocessing``:

* ``spawn``/``forkserver`` re-import the user's ``__main__`` in the child, which
  breaks scripts without an ``if __name__ == "__main__"`` guard;
* the worker starts its own session, so on timeout we kill the whole process
  group -- the worker *and* the Fast Downward translator/search processes it
  started -- with one ``killpg``;
* nothing is pickled: a task read from PDDL travels as its text, a task plan_bridge
  built (a :class:`~plan_bridge.pddl.spec.ProblemSpec`) as JSON data, a problem
  built in code by a user as the text UP's PDDLWriter writes; the plan comes back as
  action and object names.

Workers are kept warm in a :class:`WorkerPool`: unified-planning is imported once
per worker (about 0.5 s), and a worker is only replaced after it was killed.
The worker side (what runs in the process) is :mod:`plan_bridge.planning.service`.
:meth:`WorkerPool.has_ready_worker` tells whether a solve would wait for a worker
(starting, or parsing a primed problem): the warm search then runs in the calling
process instead (:mod:`plan_bridge.planning.warm`).

**Replans do not re-parse.** A worker keeps the last :data:`BASE_CACHE_SIZE` parsed
problems, keyed by a hash of their PDDL text (a :class:`ProblemText`). A request
names its base problem by that key and may carry new initial facts and a new goal
(lists of atoms); the worker derives the problem to solve from the parsed base
(a copy with those facts and goal atoms changed) instead of parsing PDDL again,
which costs up to ~1.5 s on large problems. The PDDL text is only sent when the
worker has not seen the key yet (the client mirrors each worker's cache, and a
worker that does not know the key answers ``missing-base``, upon which the text
is sent within the same deadline).

**The first parse overlaps the client's.** :meth:`WorkerPool.prime` hands a
problem's text to an idle worker without waiting (``load_task(..., prime=pool)``
does it before parsing the same text itself), so the worker parses while this
process parses, on the other core, and the first solve finds the parse ready.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from plan_bridge.errors import WorkerError
from plan_bridge.pddl.source import ProblemText

__all__ = ["ProblemText", "SolveReply", "Worker", "WorkerPool", "default_pool"]

STARTUP_TIMEOUT_S = 60.0
_KILL_GRACE_S = 0.2
#: Parsed problems a worker keeps (least recently used ones are dropped).
BASE_CACHE_SIZE = 8


@dataclass(frozen=True)
class SolveReply:
    """What a worker answered (or what happened to it)."""

    outcome: str
    """``"result"`` (engine returned), ``"error"`` (engine raised), ``"timeout"``
    (killed at the deadline), ``"cancelled"`` (killed on the caller's request) or
    ``"crashed"`` (worker died)."""
    status: str = ""
    """The UP ``PlanGenerationResultStatus`` name, for ``"result"``."""
    plan: tuple[tuple[str, tuple[str, ...]], ...] = ()
    message: str = ""
    error_type: str = ""
    warnings: tuple[str, ...] = ()
    log: str = ""
    engine_time_s: float = 0.0
    parse_time_s: float = 0.0
    """Time the worker spent parsing PDDL for this solve (0 when it reused a parse)."""
    reused: bool = False
    """True when the worker derived the problem from a base it had parsed before."""
    timing: tuple[tuple[float, float | None], ...] = ()
    """(start, duration) of each plan action in plan time (seconds), when the engine
    returned a time-triggered plan; empty for sequential plans."""


class Worker:
    """One worker process (used by one solve at a time)."""

    def __init__(self) -> None:
        # Kept open for the worker's lifetime (closed in kill()): its tail explains crashes.
        self._stderr = tempfile.TemporaryFile(prefix="plan-bridge-worker-")  # noqa: SIM115
        # The worker must import this very plan_bridge, even from a source checkout
        # that is not installed; an installed package's root is already on sys.path.
        package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        bootstrap = (
            f"import sys; root = {package_root!r}\n"
            "if root not in sys.path: sys.path.insert(0, root)\n"
            "from plan_bridge.planning.service import main; main()"
        )
        self.process = subprocess.Popen(
            [sys.executable, "-c", bootstrap],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            start_new_session=True,
            text=True,
            encoding="utf-8",
        )
        self._replies: queue.Queue[dict[str, Any] | None] = queue.Queue()
        self._ready = threading.Event()
        # Ids of prime requests whose parse has not finished (the worker is busy).
        self._parsing: set[int] = set()
        self._reader = threading.Thread(
            target=self._read_replies, name=f"plan-bridge-worker-{self.process.pid}", daemon=True
        )
        self._reader.start()
        self._next_id = 0
        # Requests are written whole, one at a time (a prime writes from its own thread).
        self._write_lock = threading.Lock()
        # Mirror of the worker's cache of parsed problems (same size and order).
        self._bases: OrderedDict[str, None] = OrderedDict()

    @property
    def pid(self) -> int:
        return self.process.pid

    def is_alive(self) -> bool:
        return self.process.poll() is None

    def _read_replies(self) -> None:
        stdout = self.process.stdout
        assert stdout is not None
        for line in stdout:
            try:
                message = json.loads(line)
            except ValueError:
                continue
            if message.get("ready"):
                self._ready.set()
            elif message.get("id") in self._parsing:
                self._parsing.discard(message["id"])  # a prime's parse is done
            else:
                self._replies.put(message)
        self._ready.set()
        self._replies.put(None)

    def is_ready(self) -> bool:
        """Whether the worker has started (imported unified-planning) and serves."""
        return self._ready.is_set() and self.is_alive()

    def is_parsing(self) -> bool:
        """Whether the worker is still parsing a primed problem."""
        return bool(self._parsing)

    def wait_ready(self, timeout: float = STARTUP_TIMEOUT_S) -> None:
        if not self._ready.wait(timeout) or not self.is_alive():
            detail = self.stderr_tail()
            self.kill()
            raise WorkerError(
                "the planner worker process did not start"
                + (f": {detail}" if detail else f" within {timeout:.0f} s")
            )

    def knows(self, key: str) -> bool:
        """Whether this worker (probably) holds the parse of base problem ``key``."""
        return key in self._bases

    def prime(self, base: ProblemText) -> None:
        """Have the worker parse ``base`` into its cache; returns at once.

        The request is written from a short-lived thread: the worker reads its
        input only once unified-planning is imported, and a large problem's text
        does not fit in the pipe's buffer. The reply (``parsed`` or an error) is
        skipped by the next exchange; if the parse failed, the next solve gets
        ``missing-base`` and sends the text again.
        """
        self._next_id += 1
        self._parsing.add(self._next_id)
        line = json.dumps({"op": "parse", "id": self._next_id, "base": base.key, **base.fields()})
        self._remember(base.key)
        # Take the lock before the thread starts, so that a request sent after this
        # call is written after the parse request.
        self._write_lock.acquire()
        threading.Thread(
            target=self._write_and_release, args=(line,), name="plan-bridge-prime", daemon=True
        ).start()

    def _write_and_release(self, line: str) -> None:
        try:
            stdin = self.process.stdin
            assert stdin is not None
            with contextlib.suppress(OSError, ValueError):
                stdin.write(line + "\n")
                stdin.flush()
        finally:
            self._write_lock.release()

    def solve(
        self,
        engine: str,
        base: ProblemText,
        timeout: float,
        *,
        init: Iterable[Sequence[str]] | None = None,
        goal: Iterable[Sequence[str]] | None = None,
        values: Iterable[Sequence[Any]] | None = None,
        engine_timeout: bool = True,
        params: Mapping[str, Any] | None = None,
        cancel: threading.Event | None = None,
        workdir: bool = True,
    ) -> SolveReply:
        """Solve ``base`` (with ``init`` as its true initial facts and ``goal`` as its
        goal conjunction, when given; ``values``: ``[fluent, *args, number]`` initial
        values of numeric atoms); kill the worker if it does not answer within
        ``timeout``. ``params`` go to the engine (UP ``OneshotPlanner(params=...)``,
        e.g. a Fast Downward search configuration); setting ``cancel`` kills the
        worker and returns the outcome ``"cancelled"`` (a portfolio stops the
        members that lost). ``workdir=False``: the engine writes no files (the warm
        search), so the solve gets no working directory."""
        self.wait_ready()
        folder = tempfile.mkdtemp(prefix="plan-bridge-solve-") if workdir else None
        request: dict[str, Any] = {
            "engine": engine,
            "base": base.key,
            "init": None if init is None else [list(fact) for fact in init],
            "goal": None if goal is None else [list(atom) for atom in goal],
            "values": None if values is None else [list(entry) for entry in values],
            # The engine's own limit is a courtesy (Fast Downward then stops cleanly
            # and reports TIMEOUT); the kill below is what makes the limit hard.
            "timeout": timeout if engine_timeout else None,
            "workdir": folder,
            "params": dict(params) if params else None,
        }
        started = time.monotonic()
        deadline = started + timeout + _KILL_GRACE_S
        try:
            send_text = base.key not in self._bases
            while True:
                if send_text:
                    request.update(base.fields())
                reply = self._exchange(request, deadline, timeout, started, cancel)
                if isinstance(reply, SolveReply):
                    self._bases.pop(base.key, None)
                    return reply
                if reply.get("outcome") == "missing-base" and not send_text:
                    # Our mirror of its cache was wrong: send the text after all.
                    self._bases.pop(base.key, None)
                    send_text = True
                    continue
                break
            self._remember(base.key)
            entries = reply.get("plan", [])
            return SolveReply(
                outcome=str(reply["outcome"]),
                status=str(reply.get("status", "")),
                plan=tuple((str(entry[0]), tuple(str(a) for a in entry[1])) for entry in entries),
                timing=tuple(
                    (float(entry[2]), None if entry[3] is None else float(entry[3]))
                    for entry in entries
                    if len(entry) == 4
                ),
                message=str(reply.get("message", "")),
                error_type=str(reply.get("error_type", "")),
                warnings=tuple(str(w) for w in reply.get("warnings", [])),
                log=str(reply.get("log", "")),
                engine_time_s=float(reply.get("engine_time_s", 0.0)),
                parse_time_s=float(reply.get("parse_time_s", 0.0)),
                reused=bool(reply.get("reused", False)),
            )
        finally:
            if folder is not None:
                shutil.rmtree(folder, ignore_errors=True)

    def _remember(self, key: str) -> None:
        self._bases[key] = None
        self._bases.move_to_end(key)
        while len(self._bases) > BASE_CACHE_SIZE:
            self._bases.popitem(last=False)

    def _exchange(
        self,
        request: dict[str, Any],
        deadline: float,
        timeout: float,
        started: float,
        cancel: threading.Event | None = None,
    ) -> dict[str, Any] | SolveReply:
        """Send one request and wait for its reply until ``deadline``."""
        self._next_id += 1
        request_id = request["id"] = self._next_id
        stdin = self.process.stdin
        assert stdin is not None
        line = json.dumps(request) + "\n"
        if not self._write_lock.acquire(timeout=max(0.0, deadline - time.monotonic())):
            return self._killed("timeout", timeout, started)
        try:
            stdin.write(line)
            stdin.flush()
        except (OSError, ValueError):
            return SolveReply("crashed", message=self._crash_message())
        finally:
            self._write_lock.release()
        while True:
            left = max(0.0, deadline - time.monotonic())
            try:
                # With a cancel event, wake up every 20 ms to look at it.
                reply = self._replies.get(timeout=left if cancel is None else min(left, 0.02))
            except queue.Empty:
                if cancel is not None and left > 0.02:
                    if not cancel.is_set():
                        continue
                    return self._killed("cancelled", timeout, started)
                return self._killed("timeout", timeout, started)
            if reply is None:
                return SolveReply("crashed", message=self._crash_message())
            if reply.get("id") == request_id:
                return reply

    def _killed(self, outcome: str, timeout: float, started: float) -> SolveReply:
        """Kill the process and say why: ``"timeout"`` (no answer within ``timeout``
        seconds) or ``"cancelled"``."""
        self.kill()
        why = "cancelled" if outcome == "cancelled" else f"no answer within {timeout:g} s"
        return SolveReply(
            outcome,
            message=f"{why}: killed the planner process",
            engine_time_s=time.monotonic() - started,
        )

    def _crash_message(self) -> str:
        code = self.process.wait(timeout=5)
        tail = self.stderr_tail()
        return f"the planner process died (exit code {code})" + (f": {tail}" if tail else "")

    def stderr_tail(self, limit: int = 600) -> str:
        with contextlib.suppress(OSError, ValueError):
            self._stderr.seek(0, os.SEEK_END)
            size = self._stderr.tell()
            self._stderr.seek(max(0, size - limit))
            return self._stderr.read().decode("utf-8", "replace").strip()
        return ""

    def kill(self) -> None:
        """Kill the worker and every process it started."""
        if self.process.poll() is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.process.pid, signal.SIGKILL)
            with contextlib.suppress(ProcessLookupError):
                self.process.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(timeout=5)
        self._close_pipes()

    def close(self) -> None:
        """Ask the worker to exit; kill it if it does not."""
        if self.process.poll() is None:
            with contextlib.suppress(OSError, ValueError):
                assert self.process.stdin is not None
                self.process.stdin.close()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=1.0)
        self.kill()

    def _close_pipes(self) -> None:
        for stream in (self.process.stdin, self.process.stdout):
            with contextlib.suppress(OSError, ValueError):
                if stream is not None:
                    stream.close()
        with contextlib.suppress(OSError, ValueError):
            self._stderr.close()


class WorkerPool:
    """Warm worker processes shared by all planners of this process.

    A solve borrows an idle worker (or starts one, up to ``max_workers``; beyond
    that it waits), and gives it back afterwards unless the worker was killed.
    Thread-safe.
    """

    def __init__(self, max_workers: int | None = None) -> None:
        self.max_workers = max_workers or max(2, os.cpu_count() or 2)
        self._idle: list[Worker] = []
        self._count = 0
        self._closed = False
        self._condition = threading.Condition()
        self._pid = os.getpid()

    def warm_up(self, count: int = 1) -> None:
        """Start workers now (without waiting for them) so later solves find one ready."""
        with self._condition:
            while len(self._idle) < count and self._count < self.max_workers:
                self._idle.append(Worker())
                self._count += 1

    def has_ready_worker(self) -> bool:
        """Whether an idle worker has started and is not parsing (a solve would not
        wait for a process to start or for a parse to end)."""
        with self._condition:
            return any(worker.is_ready() and not worker.is_parsing() for worker in self._idle)

    def prime(self, base: ProblemText) -> None:
        """Start parsing ``base`` in an idle worker (starting one if the pool may),
        without waiting; later solves of ``base`` prefer that worker. Does nothing
        when a worker already holds it or every worker is busy."""
        with self._condition:
            if self._closed:
                return
            self._idle = [w for w in self._idle if w.is_alive() or self._forget(w)]
            if any(w.knows(base.key) for w in self._idle):
                return
            fresh = [w for w in self._idle if not w._bases]
            if fresh:
                worker = fresh[-1]
            elif self._count < self.max_workers:
                worker = Worker()
                self._idle.append(worker)
                self._count += 1
            elif self._idle:
                worker = self._idle[-1]
            else:
                return
            worker.prime(base)

    def _forget(self, worker: Worker) -> bool:
        """Account for a dead idle worker (call with the condition held); False."""
        self._count -= 1
        worker.kill()
        return False

    @contextlib.contextmanager
    def worker(self, prefer: str | None = None) -> Any:
        """Borrow a worker; ``prefer``: a base problem key, to get an idle worker that
        has that problem parsed already (if there is one)."""
        worker = self._acquire(prefer)
        try:
            yield worker
        finally:
            self._release(worker)

    def _acquire(self, prefer: str | None = None) -> Worker:
        with self._condition:
            while True:
                if self._closed:
                    raise WorkerError("the planner worker pool is closed")
                if prefer is not None:
                    for index, candidate in enumerate(self._idle):
                        if candidate.knows(prefer) and candidate.is_alive():
                            return self._idle.pop(index)
                while self._idle:
                    worker = self._idle.pop()
                    if worker.is_alive():
                        return worker
                    self._count -= 1
                    worker.kill()
                if self._count < self.max_workers:
                    self._count += 1
                    break
                self._condition.wait()
        try:
            return Worker()
        except Exception:
            with self._condition:
                self._count -= 1
                self._condition.notify()
            raise

    def _release(self, worker: Worker) -> None:
        with self._condition:
            if worker.is_alive() and not self._closed:
                self._idle.append(worker)
            else:
                self._count -= 1
                worker.kill()
            self._condition.notify()

    def close(self) -> None:
        """Stop every idle worker; workers in use stop when returned."""
        with self._condition:
            self._closed = True
            idle, self._idle = self._idle, []
            self._count -= len(idle)
            self._condition.notify_all()
        if os.getpid() != self._pid:
            return  # inherited through fork: the workers belong to the parent
        stopped = 0
        try:
            for worker in idle:
                if worker.is_ready():
                    worker.close()
                else:
                    # Still importing unified-planning (it reads no input before that):
                    # waiting for it to see the closed input would delay our exit.
                    worker.kill()
                stopped += 1
        except KeyboardInterrupt:
            # Ctrl-C while a worker takes its time to exit: kill the rest (no waiting
            # for them to exit on their own), then let the interrupt go on.
            for worker in idle[stopped:]:
                worker.kill()
            raise


_pool: WorkerPool | None = None
_pool_lock = threading.Lock()


def default_pool() -> WorkerPool:
    """The process-wide pool (created on first use, closed at exit)."""
    global _pool
    with _pool_lock:
        if _pool is None or _pool._pid != os.getpid():
            _pool = WorkerPool()
        return _pool


def _close_default_pool() -> None:
    """At exit: stop the default pool's workers.

    A Ctrl-C meanwhile (the run has ended and said so; this is the process shutting
    down) ends the process at once, quietly, with the status of an interrupt (130):
    the workers were killed, and nothing is left to report.
    """
    if _pool is None or _pool._pid != os.getpid():
        return
    try:
        _pool.close()
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a third Ctrl-C changes nothing
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(130)


def _forget_pool_after_fork() -> None:
    # A forked child must not talk to its parent's workers.
    global _pool, _pool_lock
    _pool = None
    _pool_lock = threading.Lock()


atexit.register(_close_default_pool)
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool_after_fork)
