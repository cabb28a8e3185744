"""The temporal network of a time-triggered plan: which points of which steps a
step's start and end wait for.

A step *interferes* with another when one writes an atom (or a number) the other
reads or writes (:func:`footprints`, found by running the action's conditions and
effects against a state that records what they read). A dependent step waits for
the earlier step's **end** when the plan starts it after that end, else for its
**start** (the two overlap in the plan), plus the planned lag between those points
(:func:`precedence`). A step's end waits for the points planned before it of the
steps it interferes with, and for the end of an interfering step nested in it that
is planned to end at the same instant (:func:`end_precedence`).
:class:`~plan_bridge.execution.temporal.TemporalDispatch` runs a plan on these edges.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

from plan_bridge.execution.semantics import ActionModel, GroundAction
from plan_bridge.pddl.task import Fact
from plan_bridge.planning.types import PlanStep

__all__ = [
    "EPSILON",
    "Edge",
    "Footprint",
    "end_precedence",
    "footprints",
    "is_temporal",
    "precedence",
    "retimed",
]

#: Plan times closer than this are the same instant (engines separate by epsilon).
EPSILON = 1e-6


def is_temporal(steps: Sequence[PlanStep]) -> bool:
    """Whether ``steps`` is a time-triggered plan (its steps carry start times)."""
    return any(step.start is not None for step in steps)


@dataclass(frozen=True)
class Edge:
    """Step ``after`` waits for the ``point`` (``start``/``end``) of step ``before``
    and then ``lag`` plan seconds."""

    before: int
    after: int
    point: str
    lag: float


class _Recorder(set[Fact]):
    """A state that records which atoms and numbers a condition reads."""

    def __init__(self, answer: bool) -> None:
        super().__init__()
        self.answer = answer
        self.read: set[Fact] = set()
        self.values = _RecordingValues(self.read)

    def __contains__(self, fact: object) -> bool:
        if isinstance(fact, tuple):
            self.read.add(fact)
        return self.answer


class _RecordingValues(Mapping[Fact, float]):
    def __init__(self, read: set[Fact]) -> None:
        self.read = read

    def __getitem__(self, key: Fact) -> float:
        self.read.add(key)
        return 1.0

    def __iter__(self) -> Iterator[Fact]:
        return iter(())

    def __len__(self) -> int:
        return 0


Footprint = tuple[set[Fact], set[Fact]]
"""The atoms (and numbers) a step reads, and those it writes."""


def _footprint(ground: GroundAction) -> Footprint:
    """(atoms read, atoms written) by an action, numbers included (conservatively:
    both outcomes of every test are explored once)."""
    reads: set[Fact] = set()
    writes: set[Fact] = set()
    for answer in (True, False):
        state = _Recorder(answer)
        ground.applicable(state)
        ground.unmet_preconditions(state)
        ground.unmet_invariant(state)
        ground.unmet_at_end(state)
        adds, dels, values = ground.all_effects(state)
        reads |= state.read
        writes |= adds | dels | set(values)
    return reads, writes


def footprints(steps: Sequence[PlanStep], model: ActionModel) -> list[Footprint]:
    """The (read, written) atoms of each step, for :func:`precedence` and
    :func:`end_precedence` (computing them is most of compiling a temporal plan)."""
    return [_footprint(model.ground(step)) for step in steps]


def end_precedence(
    steps: Sequence[PlanStep], model: ActionModel, prints: Sequence[Footprint] | None = None
) -> list[list[Edge]]:
    """For each step, the points its *end* waits for: the start and end points of the
    interfering steps planned before its end, and the end of an interfering step that
    began after it and is planned to end with it (a light held for an inspection is not
    switched off before the inspection ends, however quick the holding skill)."""
    prints = footprints(steps, model) if prints is None else prints
    starts, ends = _times(steps)
    waits: list[list[Edge]] = [[] for _ in steps]
    for i in range(len(steps)):
        for j in range(len(steps)):
            if i == j or not _interfere(prints[i], prints[j]):
                continue
            nested = starts[j] > starts[i] + EPSILON  # j began while i was under way
            for point, at in (("start", starts[j]), ("end", ends[j])):
                before = at < ends[i] - EPSILON and (point == "end" or nested)
                # A step nested in this one and planned to end at the same instant ends
                # first (PDDL's over-all conditions need not hold at the end point): the
                # door is let go once the robot passing through is through.
                together = point == "end" and nested and at <= ends[i] + EPSILON
                if before or together:
                    waits[i].append(Edge(j, i, point, 0.0))
    return waits


def precedence(
    steps: Sequence[PlanStep], model: ActionModel, prints: Sequence[Footprint] | None = None
) -> list[list[Edge]]:
    """For each step, the edges its start waits for (see the module documentation)."""
    prints = footprints(steps, model) if prints is None else prints
    starts, ends = _times(steps)
    order = sorted(range(len(steps)), key=lambda i: (starts[i], i))
    waits: list[list[Edge]] = [[] for _ in steps]
    for position, j in enumerate(order):
        for i in order[:position]:
            if not _interfere(prints[i], prints[j]):
                continue
            if starts[j] >= ends[i] - EPSILON:
                waits[j].append(Edge(i, j, "end", max(0.0, starts[j] - ends[i])))
            else:
                waits[j].append(Edge(i, j, "start", max(0.0, starts[j] - starts[i])))
    return waits


def retimed(
    steps: Sequence[PlanStep], model: ActionModel, durations: Sequence[float | None]
) -> list[PlanStep]:
    """``steps`` with ``durations`` (one per step), each started as early as the plan's
    order allows: after the end of every earlier step it interferes with that the plan
    ran before it (a millisecond after, at most, as the planner separated them), or at
    the planned lag from the start of one it overlapped. What a plan keeps after some
    of its steps were dropped or merged, without the gaps they leave."""
    prints = footprints(steps, model)
    starts, ends = _times(steps)
    order = sorted(range(len(steps)), key=lambda i: (starts[i], i))
    begin: dict[int, float] = {}
    finish: dict[int, float] = {}
    for position, j in enumerate(order):
        earliest = 0.0
        for i in order[:position]:
            if not _interfere(prints[i], prints[j]):
                continue
            if starts[j] >= ends[i] - EPSILON:
                gap = min(max(0.0, starts[j] - ends[i]), _SEPARATION)
                earliest = max(earliest, finish[i] + gap)
            else:
                earliest = max(earliest, begin[i] + max(0.0, starts[j] - starts[i]))
        begin[j] = earliest
        finish[j] = earliest + (durations[j] or 0.0)
    return [
        PlanStep(step.action, step.arguments, round(begin[i], 6), durations[i])
        for i, step in enumerate(steps)
    ]


#: The most a retimed plan keeps between dependent points (planners separate them).
_SEPARATION = 0.001


def _times(steps: Sequence[PlanStep]) -> tuple[list[float], list[float]]:
    """The planned start and end of every step (plan seconds)."""
    starts = [step.start or 0.0 for step in steps]
    return starts, [
        start + (step.duration or 0.0) for start, step in zip(starts, steps, strict=True)
    ]


def _interfere(first: Footprint, second: Footprint) -> bool:
    """Whether one of two steps writes what the other reads or writes."""
    reads_a, writes_a = first
    reads_b, writes_b = second
    return bool(writes_a & (reads_b | writes_b) or writes_b & reads_a)
