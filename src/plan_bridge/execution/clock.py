"""Whose time a run follows: the wall clock (robots, ROS) or a simulated clock.

A :class:`Clock` tells the time (:meth:`~Clock.now`, seconds) and lets a thread wait
for a time (:meth:`~Clock.sleep_until`, which returns False at once when the waiter is
preempted). The temporal dispatcher and the plan layers that run as a Concurrence also
ask it for a condition to wait on and for a place in its order for every thread they
start (:meth:`~Clock.admit`, :meth:`~Clock.turn`); on the wall clock those cost nothing
and order nothing.

:class:`WallClock` is real time: ``time.monotonic`` and real waits.

:class:`PacedClock` is the simulated time of a world in another process that paces
itself at a known rate (a robot node's ``--time-scale``): wall time scaled, real waits.

:class:`SimClock` is a simulated world's clock: time moves only when the world says so,
and a run on it is a function of its seed whatever the threads do. Its participants (the
threads admitted to it) take **turns**: exactly one of them runs at a time, and when it
waits (until a time, on a condition of the clock, or by ending) the turn goes to

* the participant that is ready now (notified, preempted, just started) with the
  lowest key (the plan step's index; the dispatcher is ``-1``), else
* the one that waits for the earliest time, ties broken by key: the clock first moves
  to that time. With a ``time_scale`` above 0 that participant first waits
  ``time_scale`` wall seconds per simulated second (at most :data:`MAX_PACE_S`; a
  preempt cuts it short), so a viewer sees the run at that pace; the order stays the
  same.

A hand-off cannot let time slip by: a step that ends notifies the dispatcher, which is
ready before the step gives up its turn, so the dispatcher runs at the same simulated
instant. A thread that is not a participant (a sequential run's only thread, a skill's
own helper thread) moves the clock itself when it sleeps: it waits the paced wall time,
then the clock is at least at the time it waited for.

A participant must not wait for another participant by other means (a plain
``threading.Event`` set by another step's thread): that one cannot run until the
first gives up its turn. Skills of simulated worlds wait on the world's clock and on
``ud.end_ready()``, which are the clock's waits.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from types import TracebackType
from typing import Protocol, runtime_checkable

__all__ = [
    "MAX_PACE_S",
    "WALL_CLOCK",
    "Clock",
    "ClockCondition",
    "HasClock",
    "PacedClock",
    "SimClock",
    "Ticket",
    "WallClock",
    "clock_of",
]

#: The longest wall wait of one paced advance of a simulated clock, seconds (a long
#: charge stays watchable).
MAX_PACE_S = 10.0
#: How often a preemptable wait on the wall looks at its preempt flag, seconds.
SLICE_S = 0.005

Interrupted = Callable[[], bool]


class Ticket:
    """A thread's place in a clock's order (:meth:`Clock.admit`)."""

    __slots__ = ("condition", "due", "granted", "interrupted", "key", "order", "pace", "state")

    def __init__(self, key: int, order: int) -> None:
        self.key = key
        self.order = order
        #: ready, running, sleeping (until ``due``), waiting (on ``condition``), gone.
        self.state = "ready"
        self.due: float | None = None
        self.condition: ClockCondition | None = None
        self.interrupted: Interrupted | None = None
        self.granted = threading.Event()
        #: Simulated seconds the clock moved to give this ticket its turn (to pace).
        self.pace = 0.0

    def __repr__(self) -> str:
        return f"Ticket(key={self.key}, state={self.state}, due={self.due})"


class ClockCondition(threading.Condition):
    """A condition variable whose waits end at a time of its clock (wall clock here)."""

    def wait_until(self, deadline: float | None) -> None:
        """Wait (lock held) for a notification, or until ``deadline`` on the clock."""
        self.wait(None if deadline is None else max(0.0, deadline - time.monotonic()))


@runtime_checkable
class Clock(Protocol):
    """The time a run follows (see the module documentation)."""

    #: Whether its seconds are simulated seconds (plan seconds), or wall seconds.
    simulated: bool

    def now(self) -> float:
        """The time, seconds."""
        ...

    def sleep_until(self, when: float, interrupted: Interrupted | None = None) -> bool:
        """Wait until :meth:`now` reaches ``when``: True; False as soon as
        ``interrupted()`` is true (a preempt), checked before waiting too."""
        ...

    def condition(self) -> ClockCondition:
        """A condition whose waits take part in the clock's order."""
        ...

    def admit(self, key: int) -> Ticket:
        """A place in the order for a thread about to start (call it from the thread
        that starts it, before starting it); the thread runs in :meth:`turn`."""
        ...

    def turn(self, ticket: Ticket) -> AbstractContextManager[None]:
        """Run the calling thread as ``ticket``'s participant (from its first turn)."""
        ...

    def discard(self, ticket: Ticket) -> None:
        """Give up an admitted ``ticket`` whose thread will not run after all."""
        ...


class WallClock:
    """Real time: ``time.monotonic()``; waits are real; nothing is ordered."""

    simulated = False

    def now(self) -> float:
        return time.monotonic()

    def sleep_until(self, when: float, interrupted: Interrupted | None = None) -> bool:
        while True:
            if interrupted is not None and interrupted():
                return False
            left = when - time.monotonic()
            if left <= 0:
                return True
            time.sleep(left if interrupted is None else min(left, SLICE_S))

    def condition(self) -> ClockCondition:
        return ClockCondition()

    def admit(self, key: int) -> Ticket:
        return Ticket(key, 0)

    def turn(self, ticket: Ticket) -> AbstractContextManager[None]:
        return contextlib.nullcontext()

    def discard(self, ticket: Ticket) -> None:
        pass


#: The wall clock (it has no state: one is enough).
WALL_CLOCK = WallClock()


class _PacedCondition(ClockCondition):
    def __init__(self, clock: PacedClock) -> None:
        super().__init__()
        self._clock = clock

    def wait_until(self, deadline: float | None) -> None:
        self.wait(None if deadline is None else max(0.0, self._clock.wall_left(deadline)))


class PacedClock(WallClock):
    """Simulated seconds of a world that paces itself in another process: ``time_scale``
    wall seconds per simulated second, counted from when the clock was made (a robot
    node of ``plan-bridge run --ros`` runs its world at that pace). Waits are real waits
    of the paced wall time; nothing is ordered (threads run as on the wall clock)."""

    simulated = True

    def __init__(self, time_scale: float) -> None:
        if time_scale <= 0:
            raise ValueError(f"a paced clock needs a time_scale above 0, got {time_scale!r}")
        self.time_scale = float(time_scale)
        self._origin = time.monotonic()

    def now(self) -> float:
        return (time.monotonic() - self._origin) / self.time_scale

    def wall_left(self, when: float) -> float:
        """Wall seconds until the clock reads ``when``."""
        return self._origin + when * self.time_scale - time.monotonic()

    def sleep_until(self, when: float, interrupted: Interrupted | None = None) -> bool:
        return WALL_CLOCK.sleep_until(time.monotonic() + self.wall_left(when), interrupted)

    def condition(self) -> ClockCondition:
        return _PacedCondition(self)


class HasClock(Protocol):
    """What has a clock: a :class:`~plan_bridge.execution.world.World`."""

    @property
    def clock(self) -> Clock: ...


def clock_of(world: HasClock | None) -> Clock:
    """The clock of ``world``, or the wall clock when there is no world."""
    return WALL_CLOCK if world is None else world.clock


class _SimCondition(ClockCondition):
    """A condition of a :class:`SimClock`: a participant that waits on it gives up its
    turn, and a notification makes its waiters ready at the same simulated instant."""

    def __init__(self, clock: SimClock) -> None:
        super().__init__()  # (reentrant: a notifier may hold it already)
        self.clock = clock
        self._held = threading.local()

    def __enter__(self) -> bool:
        entered = super().__enter__()
        self._held.depth = getattr(self._held, "depth", 0) + 1
        return entered

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._held.depth -= 1
        super().__exit__(exc_type, exc, tb)

    def wait_until(self, deadline: float | None) -> None:
        clock = self.clock
        me = clock._me()
        if me is None:  # not a participant: notified or not, it looks again
            self.wait(SLICE_S if deadline is not None else None)
            return
        with clock._lock:
            me.state, me.condition, me.due, me.interrupted = "waiting", self, deadline, None
            clock._give_up(me)
        # Released (every level this thread holds) only once the turn is given away:
        # no participant runs meanwhile.
        depth = getattr(self._held, "depth", 0)
        for _ in range(depth):
            self.release()
        try:
            clock._await_turn(me)
        finally:
            for _ in range(depth):
                self.acquire()

    def notify_all(self) -> None:
        clock = self.clock
        with clock._lock:
            for ticket in clock._tickets:
                if ticket.state == "waiting" and ticket.condition is self:
                    ticket.state, ticket.condition, ticket.due = "ready", None, None
            if clock._me() is None:
                clock._nudge.set()  # from outside (a preempt): a paced wait ends now
            clock._dispatch()  # (nothing while a participant runs: it is that one's turn)
        super().notify_all()  # waiters that are not participants


class SimClock:
    """A simulated clock whose participants take turns in simulated time (see the
    module documentation). ``time_scale``: wall seconds per simulated second when it
    moves (0: it jumps)."""

    simulated = True

    def __init__(self, start: float = 0.0, *, time_scale: float = 0.0) -> None:
        if time_scale < 0:
            raise ValueError(f"time_scale must be 0 or more, got {time_scale!r}")
        self.time_scale = time_scale
        self._now = float(start)
        self._lock = threading.Lock()
        self._tickets: list[Ticket] = []
        self._holder: Ticket | None = None
        self._admitted = 0
        self._local = threading.local()
        self._nudge = threading.Event()

    def __repr__(self) -> str:
        return f"SimClock(now={self._now:g}, time_scale={self.time_scale:g})"

    def now(self) -> float:
        return self._now

    def reset(self, now: float) -> None:
        """Set the time (a restored world's clock): nothing happens meanwhile."""
        with self._lock:
            self._now = float(now)

    def taking_part(self) -> bool:
        """Whether the calling thread is a participant (between its turn's start and end)."""
        return self._me() is not None

    # -- the time passes -------------------------------------------------------------------
    def advance(self, seconds: float) -> None:
        """Move the clock on by ``seconds`` at once, without waiting (for a thread that
        is not a participant: it alone says when time passes)."""
        if seconds > 0:
            with self._lock:
                self._now += seconds

    def pace(self, seconds: float) -> None:
        """Wait the wall time of ``seconds`` simulated seconds (``time_scale``)."""
        wall = min(seconds * self.time_scale, MAX_PACE_S)
        if wall > 0:
            time.sleep(wall)

    def sleep(self, seconds: float, interrupted: Interrupted | None = None) -> bool:
        """:meth:`sleep_until` ``seconds`` from now."""
        return self.sleep_until(self._now + seconds, interrupted)

    def sleep_until(self, when: float, interrupted: Interrupted | None = None) -> bool:
        if interrupted is not None and interrupted():
            return False
        me = self._me()
        if me is None:
            return self._sleep_alone(when, interrupted)
        if when <= self._now:
            return True
        with self._lock:
            me.state, me.due, me.interrupted = "sleeping", when, interrupted
            self._give_up(me)
        self._await_turn(me)
        return not (interrupted is not None and interrupted())

    def _sleep_alone(self, when: float, interrupted: Interrupted | None) -> bool:
        """A thread that is not a participant: pace, then move the clock itself."""
        begin = self._now
        wall = min((when - begin) * self.time_scale, MAX_PACE_S)
        if wall > 0:
            started = time.monotonic()
            end = started + wall
            while (left := end - time.monotonic()) > 0:
                if interrupted is not None and interrupted():
                    # Stopped on the way: only the time that passed was spent.
                    passed = (time.monotonic() - started) / wall * (when - begin)
                    with self._lock:
                        self._now = max(self._now, begin + passed)
                    return False
                time.sleep(left if interrupted is None else min(left, SLICE_S))
        if interrupted is not None and interrupted():
            return False
        with self._lock:
            self._now = max(self._now, when)
        return True

    # -- participants ----------------------------------------------------------------------
    def condition(self) -> ClockCondition:
        return _SimCondition(self)

    def admit(self, key: int) -> Ticket:
        with self._lock:
            ticket = Ticket(key, self._admitted)
            self._admitted += 1
            self._tickets.append(ticket)
        return ticket

    @contextlib.contextmanager
    def turn(self, ticket: Ticket) -> Iterator[None]:
        outer = self._me()
        if outer is not None:
            # Already a participant (a dispatcher inside a step): it goes on as itself.
            self.discard(ticket)
            yield
            return
        self._local.ticket = ticket
        try:
            with self._lock:
                self._dispatch()
            self._await_turn(ticket)
            yield
        finally:
            self._local.ticket = None
            self.discard(ticket)

    def discard(self, ticket: Ticket) -> None:
        with self._lock:
            if ticket.state == "gone":
                return
            ticket.state = "gone"
            self._tickets.remove(ticket)
            if self._holder is ticket:
                self._holder = None
            self._dispatch()

    # -- the order (call with the lock held) ----------------------------------------------
    def _me(self) -> Ticket | None:
        ticket: Ticket | None = getattr(self._local, "ticket", None)
        return ticket

    def _give_up(self, me: Ticket) -> None:
        me.granted.clear()
        if self._holder is me:
            self._holder = None
        self._dispatch()

    def _dispatch(self) -> None:
        """Give the turn to the next participant, if nobody has it."""
        if self._holder is not None:
            return
        now = self._now
        best: tuple[float, int, int] | None = None
        chosen: Ticket | None = None
        for ticket in self._tickets:
            state = ticket.state
            if state == "ready":
                at = now
            elif state == "sleeping":
                interrupted = ticket.interrupted
                due = ticket.due if ticket.due is not None else now
                at = now if interrupted is not None and interrupted() else due
            elif state == "waiting" and ticket.due is not None:
                at = ticket.due
            else:
                continue
            rank = (max(at, now), ticket.key, ticket.order)
            if best is None or rank < best:
                best, chosen = rank, ticket
        if chosen is None or best is None:
            return  # idle: every participant waits on a condition (or none is left)
        ticket = chosen
        ticket.pace = best[0] - now
        self._now = best[0]
        ticket.state, ticket.due, ticket.condition = "running", None, None
        self._holder = ticket
        ticket.granted.set()

    def _await_turn(self, me: Ticket) -> None:
        """Block until ``me`` has the turn; then pace the time the clock moved for it
        (cut short by a preempt of ``me``, or a notification from outside)."""
        me.granted.wait()
        seconds, me.pace = me.pace, 0.0
        wall = min(seconds * self.time_scale, MAX_PACE_S)
        if wall <= 0:
            return
        interrupted = me.interrupted
        self._nudge.clear()
        end = time.monotonic() + wall
        while (left := end - time.monotonic()) > 0:
            if (interrupted is not None and interrupted()) or self._nudge.is_set():
                return
            time.sleep(min(left, SLICE_S))
