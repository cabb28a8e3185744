"""A fleet's goal shared out: the goal's atoms grouped into jobs, jobs given to robots.

A **job** is a group of goal atoms that one robot can see to: atoms that share an
object (``(At cup table)`` and ``(HandEmpty r)`` while ``r`` holds the cup...) are one
job; an atom that names a robot binds its job to that robot. :func:`allocate` gives
the jobs to robots by route cost on the map: a robot's cost of a job is the drive to
where the job starts (the object's place) and on to where it ends, at the robot's
speed; jobs go, one at a time, to the robot that would finish it first counting what
it already has to do (the greedy rule fleet managers use). A job whose object a robot
holds is that robot's.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from plan_bridge.maps.tasks import RouteTasks, whereabouts
from plan_bridge.pddl.task import Fact

__all__ = ["Job", "allocate", "jobs_of"]


@dataclass(frozen=True)
class Job:
    """Goal atoms one robot sees to."""

    atoms: tuple[Fact, ...]
    robot: str | None = None
    """The robot the atoms name (None: any robot)."""
    start: str | None = None
    """Where the job begins (the place of its object, or of its gate); lower case."""
    end: str | None = None
    """Where it ends (where its object goes, where its robot is to be); lower case."""

    def __str__(self) -> str:
        return " ".join("(" + " ".join(atom) + ")" for atom in self.atoms)


@dataclass
class _Union:
    parent: dict[str, str] = field(default_factory=dict)

    def find(self, key: str) -> str:
        self.parent.setdefault(key, key)
        while self.parent[key] != key:
            self.parent[key] = self.parent[self.parent[key]]
            key = self.parent[key]
        return key

    def join(self, a: str, b: str) -> None:
        self.parent[self.find(a)] = self.find(b)


def jobs_of(
    goal: Sequence[Fact], robots: Iterable[str], facts: Iterable[Fact], view: RouteTasks
) -> list[Job]:
    """The jobs of ``goal`` (lower-case atoms) for ``robots`` in the belief ``facts``."""
    fleet = set(robots)
    where, holder = whereabouts(facts)
    groups = _Union()
    for index, atom in enumerate(goal):
        key = f"#{index}"
        groups.find(key)
        for name in _movables(atom):
            groups.join(key, f"@{name}")
            if name in holder:  # what a robot holds is that robot's to see to
                groups.join(key, f"@{holder[name]}")
    members: dict[str, list[Fact]] = {}
    for index, atom in enumerate(goal):
        members.setdefault(groups.find(f"#{index}"), []).append(atom)
    jobs = []
    for atoms in members.values():
        named = sorted({n for atom in atoms for n in _movables(atom)} & fleet)
        held = sorted({holder[n] for atom in atoms for n in _movables(atom) if n in holder})
        bound = named[0] if named else held[0] if held else None
        start, end = _ends(atoms, where, view)
        jobs.append(Job(tuple(atoms), bound, start, end))
    return jobs


def _movables(atom: Fact) -> list[str]:
    """The robots and objects an atom is about (not its places or gates)."""
    name, *args = atom
    if name == "at":
        return [args[0]]
    if name == "has":
        return [args[1]]
    if name in ("holding",):
        return list(args)
    if name in ("handempty", "charged"):
        return [args[0]]
    return []


def _ends(
    atoms: Sequence[Fact], where: dict[str, str], view: RouteTasks
) -> tuple[str | None, str | None]:
    """Where a job begins and ends, as far as its atoms tell."""
    start: str | None = None
    end: str | None = None
    for atom in atoms:
        name, *args = atom
        if name == "at":
            start = start or where.get(args[0])
            end = end or args[1]
        elif name == "has":
            start = start or where.get(args[1])
            places = view.model.spawn_places(view.name(args[0]))
            end = end or (places[0].lower() if places else None)
        elif name == "holding":
            start = start or where.get(args[1])
        elif name in ("isopen", "islocked", "searched"):
            target = args[0] if name == "searched" else _gate_place(view, args[0])
            start = start or target
            end = end or target
    return start, end or start


def _gate_place(view: RouteTasks, gate: str) -> str | None:
    places = view.model.gate_places(view.name(gate))
    return places[0].lower() if places else None


def allocate(
    jobs: Sequence[Job],
    robots: Sequence[str],
    facts: Iterable[Fact],
    view: RouteTasks,
    closed: frozenset[str],
) -> dict[str, list[Job]]:
    """Each robot's jobs (see the module's doc); every job goes to one robot. Routes
    go round the hallways ``closed``."""
    where, _ = whereabouts(facts)
    place: dict[str, str | None] = {r: where.get(r) for r in robots}
    busy = dict.fromkeys(robots, 0.0)
    speed = {r: max(view.model.robot(view.name(r)).speed, 1e-6) for r in robots}
    plan: dict[str, list[Job]] = {r: [] for r in robots}
    free = [job for job in jobs if job.robot is None or job.robot not in plan]
    for job in jobs:
        if job.robot is not None and job.robot in plan:
            metres = _job_metres(view, place[job.robot], job, closed)
            busy[job.robot] += metres / speed[job.robot]
            plan[job.robot].append(job)
            place[job.robot] = job.end or place[job.robot]
    while free:
        best: tuple[float, int, str] | None = None
        for index, job in enumerate(free):
            for robot in robots:
                metres = _job_metres(view, place[robot], job, closed)
                finish = busy[robot] + metres / speed[robot]
                if best is None or finish < best[0]:
                    best = (finish, index, robot)
        assert best is not None
        finish, index, robot = best
        job = free.pop(index)
        busy[robot] = finish
        plan[robot].append(job)
        place[robot] = job.end or place[robot]
    return {robot: jobs_ for robot, jobs_ in plan.items() if jobs_}


def _job_metres(view: RouteTasks, start: str | None, job: Job, closed: frozenset[str]) -> float:
    """Metres of driving a job takes a robot at ``start`` (infinite: no way)."""
    legs = [(start, job.start), (job.start, job.end)]
    total = 0.0
    for a, b in legs:
        if a is None or b is None or a == b:
            continue
        lengths = view.graph.lengths_from(view.name(a), closed)
        metres = lengths.get(view.name(b))
        if metres is None:
            return math.inf
        total += metres
    return total
