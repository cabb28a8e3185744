"""Wall-clock pacing of a simulated world, so that a robot node's skills take time.

A domain's simulated world (``domains/NAME/world.py``) counts the seconds its robot
spends in :attr:`~plan_bridge.execution.simulation.SimulatedWorld.sim_time` and never sleeps:
a whole mission runs in milliseconds. A robot node serving the domain's skills over
ROS 2 should behave like a robot instead: a skill takes time, streams progress, and a
cancel stops the motion in progress. :func:`pace` does that without touching the
domain's code: every advance of ``sim_time`` by ``dt`` simulated seconds, made by a
thread that runs a skill (:meth:`Pacer.running`), first waits ``dt * time_scale``
wall seconds. When that skill is halted (:meth:`Run.halt`, on a cancel), the wait
ends at once, the clock advances only by the time that really passed, and
:class:`HaltedError` is raised inside the world's primitive (``drive``, ``grasp``...)
*before* it changes any fact: the motion stopped, so it had no effect.

Threads that are not running a skill (a snapshot, the ``info`` service) are never
slowed down.

A pyrobosim world (:class:`~plan_bridge.robosim.world.RobosimWorld`) is not paced here:
its actions already take wall time (pyrobosim's path executor, paced waits), so the
robot node sets its own ``time_scale`` instead (drives at pyrobosim's real-time factor
``1 / time_scale``, other actions wait ``time_scale`` times their duration, both
stopped by a preempt).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from plan_bridge.execution.simulation import SimulatedWorld

__all__ = ["HaltedError", "Pacer", "Run", "pace"]


class HaltedError(Exception):
    """Raised inside the world when the motion of a halted skill is stopped.

    ``fraction`` is the part of the motion's duration that passed before it stopped.
    """

    def __init__(self, message: str, fraction: float = 0.0) -> None:
        super().__init__(message)
        self.fraction = fraction


class Run:
    """One skill execution: the thread that paces it and its halt flag."""

    def __init__(self) -> None:
        self._halt = threading.Event()

    @property
    def halted(self) -> bool:
        return self._halt.is_set()

    def halt(self) -> None:
        """Stop the motion in progress (and every later one) of this run."""
        self._halt.set()

    def wait(self, seconds: float) -> float:
        """Wait up to ``seconds`` (wall); return the fraction that passed (1.0 if all)."""
        if seconds <= 0:
            return 1.0
        started = time.monotonic()
        if self._halt.wait(seconds):
            return min(1.0, (time.monotonic() - started) / seconds)
        return 1.0


class Pacer:
    """Wall seconds per simulated second (``time_scale``), per running skill thread."""

    def __init__(self, time_scale: float) -> None:
        if time_scale < 0:
            raise ValueError(f"time_scale must be >= 0, got {time_scale}")
        self.time_scale = time_scale
        self._local = threading.local()

    @contextmanager
    def running(self, run: Run) -> Iterator[Run]:
        """Pace the world's clock, as seen from this thread, for ``run``."""
        self._local.run = run
        try:
            yield run
        finally:
            self._local.run = None

    def advance(self, old: float, new: float) -> float:
        """The clock moves from ``old`` to ``new``: wait, and return where it really got.

        Raises :class:`HaltedError` (after the clock moved by the time that passed) when
        this thread's run is halted.
        """
        run: Run | None = getattr(self._local, "run", None)
        if run is None:
            return new
        if run.halted:
            raise HaltedError("the skill was halted")
        delta = new - old
        if delta <= 0 or self.time_scale <= 0:
            return new
        fraction = run.wait(delta * self.time_scale)
        if fraction < 1.0:
            raise HaltedError(
                f"the motion was stopped after {fraction * delta:.2f} of {delta:.2f} s", fraction
            )
        return new


_PACED: dict[type, type] = {}
_PACED_LOCK = threading.Lock()


_World = TypeVar("_World", bound="SimulatedWorld")


def _paced_class(cls: type) -> type:
    with _PACED_LOCK:
        paced = _PACED.get(cls)
        if paced is None:

            def get_time(self: Any) -> float:
                return float(self.__dict__.get("_paced_sim_time", 0.0))

            def set_time(self: Any, value: float) -> None:
                pacer: Pacer | None = self.__dict__.get("_pacer")
                old = get_time(self)
                if pacer is None:
                    self.__dict__["_paced_sim_time"] = float(value)
                    return
                try:
                    pacer.advance(old, float(value))
                except HaltedError as exc:
                    # Only the time that really passed was spent.
                    self.__dict__["_paced_sim_time"] = old + (float(value) - old) * exc.fraction
                    raise
                self.__dict__["_paced_sim_time"] = float(value)

            paced = type(
                f"Paced{cls.__name__}",
                (cls,),
                {
                    "sim_time": property(get_time, set_time),
                    # Saved through sim_time; the pacer is a connection (see SimulatedWorld).
                    "wiring": ("_pacer", "_paced_sim_time"),
                    "__doc__": f"{cls.__name__} whose clock advances in wall time (pacing.py).",
                    "__module__": cls.__module__,
                },
            )
            _PACED[cls] = paced
        return paced


def pace(world: _World, pacer: Pacer) -> _World:
    """Make ``world``'s ``sim_time`` advance in wall time for running skills (in place).

    ``world`` keeps its class's behaviour (it becomes an instance of a subclass that
    only turns ``sim_time`` into a paced property). Returns ``world``.
    """
    if "_pacer" in world.__dict__:
        world.__dict__["_pacer"] = pacer
        return world
    value = float(world.__dict__.pop("sim_time", 0.0))
    world.__class__ = _paced_class(type(world))
    world.__dict__["_paced_sim_time"] = value
    world.__dict__["_pacer"] = pacer
    return world
