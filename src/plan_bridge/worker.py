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
* nothing is pickled: the task travels as PDDL text (written by UP's PDDLWriter),
  the plan comes back as action and object names.

Workers are kept warm in a :class:`WorkerPool`: unified-planning is imported once
per worker (about 0.5 s), and a worker is only replaced after it was killed.
Run as ``python -m plan_bridge.worker`` it serves requests on stdin/stdout.
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
from dataclasses import dataclass
from typing import IO, Any

from plan_bridge.errors import WorkerError

__all__ = ["SolveReply", "Worker", "WorkerPool", "default_pool", "serve"]

STARTUP_TIMEOUT_S = 60.0
_KILL_GRACE_S = 0.2


@dataclass(frozen=True)
class SolveReply:
    """What a worker answered (or what happened to it)."""

    outcome: str
    """``"result"`` (engine returned), ``"error"`` (engine raised), ``"timeout"``
    (killed at the deadline) or ``"crashed"`` (worker died)."""
    status: str = ""
    """The UP ``PlanGenerationResultStatus`` name, for ``"result"``."""
    plan: tuple[tuple[str, tuple[str, ...]], ...] = ()
    message: str = ""
    error_type: str = ""
    warnings: tuple[str, ...] = ()
    log: str = ""
    engine_time_s: float = 0.0


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
            "from plan_bridge.worker import _main; _main()"
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
        self._reader = threading.Thread(
            target=self._read_replies, name=f"plan-bridge-worker-{self.process.pid}", daemon=True
        )
        self._reader.start()
        self._next_id = 0
        self.started_at = time.monotonic()
        self.solves = 0

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
            else:
                self._replies.put(message)
        self._ready.set()
        self._replies.put(None)

    def wait_ready(self, timeout: float = STARTUP_TIMEOUT_S) -> None:
        if not self._ready.wait(timeout) or not self.is_alive():
            detail = self.stderr_tail()
            self.kill()
            raise WorkerError(
                "the planner worker process did not start"
                + (f": {detail}" if detail else f" within {timeout:.0f} s")
            )

    def solve(
        self, engine: str, domain: str, problem: str, timeout: float, engine_timeout: bool
    ) -> SolveReply:
        """Run one solve; kill the worker if it does not answer within ``timeout``."""
        self.wait_ready()
        self._next_id += 1
        request_id = self._next_id
        workdir = tempfile.mkdtemp(prefix="plan-bridge-solve-")
        request = {
            "id": request_id,
            "engine": engine,
            "domain": domain,
            "problem": problem,
            # The engine's own limit is a courtesy (Fast Downward then stops cleanly
            # and reports TIMEOUT); the kill below is what makes the limit hard.
            "timeout": timeout if engine_timeout else None,
            "workdir": workdir,
        }
        started = time.monotonic()
        try:
            stdin = self.process.stdin
            assert stdin is not None
            try:
                stdin.write(json.dumps(request) + "\n")
                stdin.flush()
            except OSError:
                return SolveReply("crashed", message=self._crash_message())
            deadline = started + timeout + _KILL_GRACE_S
            while True:
                try:
                    reply = self._replies.get(timeout=max(0.0, deadline - time.monotonic()))
                except queue.Empty:
                    self.kill()
                    return SolveReply(
                        "timeout",
                        message=f"no answer within {timeout:g} s: killed the planner process",
                        engine_time_s=time.monotonic() - started,
                    )
                if reply is None:
                    return SolveReply("crashed", message=self._crash_message())
                if reply.get("id") == request_id:
                    break
            self.solves += 1
            return SolveReply(
                outcome=str(reply["outcome"]),
                status=str(reply.get("status", "")),
                plan=tuple(
                    (str(name), tuple(str(a) for a in args)) for name, args in reply.get("plan", [])
                ),
                message=str(reply.get("message", "")),
                error_type=str(reply.get("error_type", "")),
                warnings=tuple(str(w) for w in reply.get("warnings", [])),
                log=str(reply.get("log", "")),
                engine_time_s=float(reply.get("engine_time_s", 0.0)),
            )
        finally:
            shutil.rmtree(workdir, ignore_errors=True)

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

    @contextlib.contextmanager
    def worker(self) -> Any:
        worker = self._acquire()
        try:
            yield worker
        finally:
            self._release(worker)

    def _acquire(self) -> Worker:
        with self._condition:
            while True:
                if self._closed:
                    raise WorkerError("the planner worker pool is closed")
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
        for worker in idle:
            worker.close()


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
    if _pool is not None and _pool._pid == os.getpid():
        _pool.close()


def _forget_pool_after_fork() -> None:
    # A forked child must not talk to its parent's workers.
    global _pool, _pool_lock
    _pool = None
    _pool_lock = threading.Lock()


atexit.register(_close_default_pool)
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool_after_fork)


# -- worker side -------------------------------------------------------------------


def serve(requests: IO[str], replies: IO[str]) -> None:
    """Answer solve requests (one JSON object per line) until stdin closes."""
    from plan_bridge.up_runtime import ensure_unified_planning

    ensure_unified_planning()
    from unified_planning.io import PDDLReader  # type: ignore[import-untyped]

    # Build the grammar once: constructing a PDDLReader costs ~50 ms.
    reader = PDDLReader()
    home = os.getcwd()
    replies.write(json.dumps({"ready": True, "pid": os.getpid()}) + "\n")
    replies.flush()
    for line in requests:
        if not line.strip():
            continue
        request = json.loads(line)
        try:
            os.chdir(request["workdir"])
            reply = _solve_request(reader, request)
        except Exception as exc:
            reply = {"outcome": "error", "error_type": type(exc).__name__, "message": str(exc)}
        finally:
            os.chdir(home)
        reply["id"] = request["id"]
        replies.write(json.dumps(reply) + "\n")
        replies.flush()


_parsed: dict[tuple[str, str], Any] = {}


def _solve_request(reader: Any, request: dict[str, Any]) -> dict[str, Any]:
    import warnings

    from unified_planning.shortcuts import OneshotPlanner  # type: ignore[import-untyped]

    key = (request["domain"], request["problem"])
    problem = _parsed.get(key)
    if problem is None:
        problem = reader.parse_problem_string(request["domain"], request["problem"])
        # Benchmarks and retries solve the same text again: parsing a large problem
        # costs more than solving it.
        if len(_parsed) >= 8:
            _parsed.pop(next(iter(_parsed)))
        _parsed[key] = problem
    started = time.monotonic()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with OneshotPlanner(name=request["engine"]) as planner:
                result = planner.solve(problem, timeout=request["timeout"])
        except Exception as exc:
            return {
                "outcome": "error",
                "error_type": type(exc).__name__,
                "message": str(exc),
                "warnings": [str(w.message) for w in caught],
                "engine_time_s": time.monotonic() - started,
            }
    plan = []
    if result.plan is not None:
        plan = [
            [instance.action.name, [arg.object().name for arg in instance.actual_parameters]]
            for instance in result.plan.actions
        ]
    log = "\n".join(m.message for m in (result.log_messages or []) if m.message.strip())
    return {
        "outcome": "result",
        "status": result.status.name,
        "plan": plan,
        "warnings": [str(w.message) for w in caught],
        "log": log[-4000:],
        "engine_time_s": time.monotonic() - started,
    }


def _main() -> None:
    # Our replies own the real stdout; anything an engine prints goes to stderr.
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "w", encoding="utf-8")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    serve(sys.stdin, replies)


if __name__ == "__main__":
    _main()
