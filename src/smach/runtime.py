"""The runtime context of a tree of states: what every state of one tree shares.

A :class:`Runtime` is made by each top-level container and handed down when a
container adopts a child (``Container.adopt_child``). It holds:

* ``bus``: the tree's :class:`~smach.events.EventBus` (its listeners);
* ``control``: the tree's step hook, a :class:`StepHook` (``smach.control.Controller``
  implements it), or ``None``; containers call it around every child they start;
* ``preempt_seen``: set when any state of the tree got a preempt request, so that
  the end of a top-level run walks the tree to clear flags only when there can be some;
* ``log_info``: whether the current top-level run writes INFO log lines (decided once
  per top-level run, read by every container below).

The core modules read these; nothing here knows about states or containers.
"""

from __future__ import annotations

from typing import Any, Protocol

from smach.events import Event, EventBus

__all__ = ["Runtime", "StepHook", "captured", "publish"]


class StepHook(Protocol):
    """What a container calls around each child it starts (runtime control).

    ``enter`` is called before the child at ``path`` starts and may block (a pause,
    a breakpoint); ``leave`` after it returned (``None`` when it raised) and returns
    the outcome the container takes (a forced one may replace it); ``wake`` makes
    held children look at their preempt flags again.
    """

    def enter(self, container: Any, path: str, state: Any) -> None: ...

    def leave(self, path: str, state: Any, outcome: str | None) -> str | None: ...

    def wake(self) -> None: ...


class Runtime:
    """The runtime context of one tree: its bus, step hook, preempt and log switches."""

    __slots__ = ("bus", "control", "log_info", "preempt_seen")

    def __init__(self, bus: EventBus | None = None) -> None:
        self.bus = bus if bus is not None else EventBus()
        # Tested once per step by the containers (None costs one attribute load).
        self.control: StepHook | None = None
        self.preempt_seen = False
        self.log_info = False

    def merge_into(self, other: Runtime) -> None:
        """Hand what was attached to this (sub)tree over to ``other``, the tree it joins.

        Listeners move over; a step hook moves over unless ``other`` has one (a
        controlled subtree stays controlled).
        """
        if other is self:
            return
        for listener in self.bus.listeners:
            other.bus.add(listener)
        if other.control is None:
            other.control = self.control

    def __getstate__(self) -> dict[str, Any]:
        # Listeners and controllers watch a live run: a copy starts without them.
        return {}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__()  # type: ignore[misc]


class _Member(Protocol):
    @property
    def _rt(self) -> Runtime: ...


def captured(state: _Member) -> bool:
    """Whether a capture listener (a journal, a viewer) watches the tree ``state`` belongs
    to: an emitter whose events cost something to make (a picture) may skip them otherwise."""
    return bool(state._rt.bus.sinks)


def publish(state: _Member, event: Event) -> None:
    """Send ``event`` to every listener of the tree ``state`` belongs to (nothing when
    nobody listens): for events from outside the tree's own states, such as the
    :class:`~smach.events.SceneChanged` pictures of the world a mission runs in."""
    bus = state._rt.bus
    if bus.listeners:
        bus.emit(event)
