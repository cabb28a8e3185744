"""The tasks a planner gets of a world with a map: the places a task needs, routes
between them.

:class:`RouteTasks` is the :class:`~plan_bridge.execution.task_view.TaskView` of a
:class:`~plan_bridge.maps.model.WorldModel` and its :class:`~plan_bridge.maps.graph.PlaceMap`,
in the vocabulary of the map domain (``domain.pddl`` next to this module). From the
belief (the whole building: where every robot and object is, which hallway is open)
and a goal it makes a small task:

* **places**: where the robots are, where the goal's objects lie and are to go, the
  places of the goal's gates and spots, the chargers, and both doorways of every
  hallway believed closed but not locked (a robot may open it, hands free);
* **routes**: for every two of those places, ``(route a b)`` and ``(metres a b)`` when
  a route over the hallways believed open joins them (its length: the map's shortest
  route); a closed hallway is crossed with ``cross`` between its doorways;
* **objects**: the goal's objects and those the robots hold; gates: the closed
  hallways, the goal's, and the locations of the places' spawns.

Nothing is parsed: the task is a :class:`~plan_bridge.pddl.spec.ProblemSpec`, built
with unified-planning's API (:func:`~plan_bridge.pddl.task.task_from_spec`). The
task is made again only when what it holds changes (another place for a robot, a
hallway found closed): the same task object comes back otherwise.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from plan_bridge.belief import FactSnapshot, values_of
from plan_bridge.belief.whereabouts import absences
from plan_bridge.errors import PlanBridgeError
from plan_bridge.maps.graph import PlaceMap
from plan_bridge.maps.model import WorldModel
from plan_bridge.maps.search import NEAR_M, ObjectNotFoundError, place_weights, search_order
from plan_bridge.pddl.spec import ProblemSpec, without_actions
from plan_bridge.pddl.task import Fact, PlanningTask, task_from_spec

__all__ = [
    "DOMAIN_PATH",
    "MAP_FUNCTIONS",
    "MAP_PREDICATES",
    "RouteTasks",
    "TaskError",
    "whereabouts",
]

DOMAIN_PATH = Path(__file__).with_name("domain.pddl")
"""The map domain shipped with plan_bridge."""
#: The facts of a task that come from the map (not from the belief's state).
MAP_PREDICATES = frozenset(
    {"route", "hall-ends", "spawn-of", "reaches-gate", "is-charger", "may-hold"}
)
#: The numbers of a task that come from the map and the robots' make.
MAP_FUNCTIONS = frozenset({"metres", "drain-per-metre", "top-speed"})
#: Tasks kept (per what they hold), so a task comes back the same object.
_TASKS_KEPT = 16
#: Kairos' search preset for these tasks, with the makespan as their metric: on generated
#: buildings of 9 and 25 rooms its first plan for two deliveries has 8 steps (3 ms),
#: where its default search takes 30-60 ms for plans of 14 to 133 steps (drives to and
#: fro); without the metric, the same preset drives to and fro on robosim_fetch. The
#: first plan is taken (the same plan every time: seeded runs repeat).
SEARCH = "lama-novelty"
#: A task of several robots is improved until this many seconds pass without a shorter
#: plan: robosim_two_robots' hand_over gets its 26.5 s plan (one robot opens the locker
#: while the other brings the box) 2 ms after the first one (51.6 s: one robot does
#: everything).
TEAM_IMPROVE_S = 0.25
#: A drive of no length would be a durative action of no duration: a centimetre at least.
_MIN_METRES = 0.01


class TaskError(PlanBridgeError):
    """The belief does not say what a task needs (where a robot is)."""


@dataclass
class _Needs:
    """What a task holds besides routes."""

    robots: list[str] = field(default_factory=list)
    places: dict[str, None] = field(default_factory=dict)
    items: dict[str, None] = field(default_factory=dict)
    gates: dict[str, None] = field(default_factory=dict)
    searches: dict[str, list[str]] = field(default_factory=dict)
    """A lost object -> the places to look for it at (the best tier left)."""
    searched: dict[str, None] = field(default_factory=dict)
    """The places a lost object was looked for at: named by the task (no routes), so
    that its ``(absent OBJECT PLACE)`` facts go wherever the task's facts go."""

    def place(self, name: str | None) -> None:
        if name:
            self.places[name] = None


class RouteTasks:
    """The task view of a world with a map (see the module's doc)."""

    map_predicates = MAP_PREDICATES
    map_functions = MAP_FUNCTIONS
    domain_path = DOMAIN_PATH

    def __init__(self, model: WorldModel, graph: PlaceMap | None = None) -> None:
        self.model = model
        self.graph = graph if graph is not None else PlaceMap(model)
        self.domain_text = DOMAIN_PATH.read_text(encoding="utf-8")
        # A task with no object to look for plans without the search action: grounded
        # over every robot, object and place, it made a fleet's plans 10-20x slower.
        self._domain_without_search = without_actions(self.domain_text, ["search"])
        # PDDL is read in lower case: the world's names by their lower-case form.
        self._names = {name.lower(): name for name in model.names}
        self._tasks: OrderedDict[tuple[object, ...], PlanningTask] = OrderedDict()
        self._closed_of: weakref.WeakKeyDictionary[PlanningTask, frozenset[str]] = (
            weakref.WeakKeyDictionary()
        )
        self._lock = threading.Lock()
        # A lost object -> robot -> the place it was sent to look at (search_shares).
        self._looking: dict[str, dict[str, str]] = {}

    def name(self, pddl: str) -> str:
        """The world's name of a lower-case PDDL name."""
        return self._names.get(pddl, pddl)

    # -- the belief at the start -------------------------------------------------
    def belief(self) -> FactSnapshot:
        """Every robot, object and gate of the world as it is loaded (a new mission: the
        places robots were sent to look at, :meth:`search_shares`, are forgotten)."""
        with self._lock:
            self._looking.clear()
        model = self.model
        facts: set[Fact] = set()
        values: dict[Fact, float] = {}
        for robot in model.robots:
            facts.add(_f("At", robot.name, robot.place))
            facts.add(_f("bot-ready", robot.name))
            facts.add(
                _f("Holding", robot.name, robot.holding)
                if robot.holding
                else _f("HandEmpty", robot.name)
            )
            values[_f("battery-level", robot.name)] = round(robot.battery, 3)
        for item, spawn in model.items.items():
            place = model.spawn_place(spawn) if spawn is not None else None
            if place is None:
                continue
            facts.add(_f("At", item, place))
            fixture = model.places[place].fixture
            if fixture is not None:
                facts.add(_f("Has", fixture, item))
        for gate in model.gates.values():
            if gate.is_open:
                facts.add(_f("IsOpen", gate.name))
            if gate.is_locked:
                facts.add(_f("IsLocked", gate.name))
        return FactSnapshot(facts, values)

    def objects(self, facts: Collection[Fact] | None = None) -> dict[str, str]:
        """Every object of the world and its type (lower case): robots, objects,
        places, hallways and locations; with ``facts`` (a belief), the objects it has
        at a place that the map did not know join first (seen on the way)."""
        if facts is not None:
            self._learn(facts)
        model = self.model
        named: dict[str, str] = {r.name.lower(): "bot" for r in model.robots}
        named.update((item.lower(), "item") for item in model.items)
        named.update((place.lower(), "spot") for place in model.places)
        named.update((gate.name.lower(), gate.kind) for gate in model.gates.values())
        return named

    # -- tasks -------------------------------------------------------------------
    def task_for(
        self,
        facts: FactSnapshot,
        goal: Sequence[Fact],
        robots: Iterable[str] | None = None,
        closed: frozenset[str] | None = None,
        search_at: Mapping[str, Sequence[str]] | None = None,
        *,
        every_action: bool = False,
    ) -> PlanningTask:
        """The task of ``goal`` (atoms of the map domain) from the belief ``facts``, for
        ``robots`` (lower-case names; when None, all that the belief places, and
        :class:`TaskError` if it places none). ``closed``: the hallways to
        route round (by default those the belief does not hold open; a part of a task
        is made with the task's own, :meth:`closed_for`). ``search_at``: a lost object
        -> the places this task looks for it at (by default the first ones of
        :meth:`search_order`, one per robot; a fleet gives each robot its own).
        A task with no lost object to look for leaves the ``search`` action out,
        unless ``every_action`` (a world's task, which skills are checked against)."""
        goal = tuple(goal)
        self._learn(facts)
        if closed is None:
            closed = self._closed(facts)
        needs = self._needs(facts, goal, robots, closed, search_at or {})
        spec = self._spec(facts, goal, needs, closed, every_action or bool(needs.searches))
        key = (spec.objects, _static(spec), spec.goal, spec.domain is self.domain_text)
        with self._lock:
            cached = self._tasks.get(key)
            if cached is not None:
                self._tasks.move_to_end(key)
                return cached
        task = task_from_spec(spec)
        with self._lock:
            self._tasks[key] = task
            self._closed_of[task] = closed
            while len(self._tasks) > _TASKS_KEPT:
                self._tasks.popitem(last=False)
        return task

    def closed_for(self, task: PlanningTask) -> frozenset[str] | None:
        """The hallways ``task`` routes round (None: not a task of this view)."""
        with self._lock:
            return self._closed_of.get(task)

    def closed_halls(self, facts: Collection[Fact]) -> frozenset[str]:
        """The hallways the belief does not hold open (the map's names)."""
        return self._closed(facts)

    def robot_place(self, facts: FactSnapshot, robot: str) -> str | None:
        """Where the belief has ``robot`` (a lower-case place name), or None."""
        return whereabouts(facts)[0].get(robot)

    def robots(self) -> list[str]:
        """The robots' lower-case names."""
        return [robot.name.lower() for robot in self.model.robots]

    def _closed(self, facts: Collection[Fact]) -> frozenset[str]:
        return frozenset(hall for hall in self.model.halls if ("isopen", hall.lower()) not in facts)

    def _needs(
        self,
        facts: FactSnapshot,
        goal: Sequence[Fact],
        robots: Iterable[str] | None,
        closed: frozenset[str],
        search_at: Mapping[str, Sequence[str]],
    ) -> _Needs:
        needs = _Needs()
        where, held = whereabouts(facts)
        chosen = list(robots) if robots is not None else self.robots()
        if robots is None and any(robot in where for robot in chosen):
            # Every robot the belief places: one it cannot (whose node died mid-drive,
            # out of sight) gets no part in the task until it is seen again.
            chosen = [robot for robot in chosen if robot in where]
        for robot in chosen:
            place = where.get(robot)
            if place is None:
                raise TaskError(f"the belief does not say where {self.name(robot)} is")
            needs.robots.append(robot)
            needs.place(place)
            for item, holder in held.items():
                if holder == robot:
                    needs.items[item] = None
        for atom in goal:
            self._goal_needs(atom, needs, where, held)
        for item in list(needs.items):
            if item in where or item in held:
                needs.place(where.get(item))
                with self._lock:
                    self._looking.pop(item, None)  # found: the robots' places are free
            else:
                if item in search_at:
                    needs.searches[item] = list(search_at[item])
                    for place in needs.searches[item]:
                        needs.place(place)
                else:
                    self._search_needs(facts, item, needs, closed)
                needs.searched.update(dict.fromkeys(absences(facts, item)))
        self._gates_needed(facts, closed, needs)
        return needs

    def search_order(
        self,
        facts: FactSnapshot,
        item: str,
        robots: Iterable[str] | None = None,
        closed: frozenset[str] | None = None,
    ) -> list[str]:
        """The places (lower case) to look for lost ``item`` at, in order
        (:func:`~plan_bridge.maps.search.search_order`, the route from the nearest of
        ``robots``; all when None)."""
        if closed is None:
            closed = self._closed(facts)
        where, _ = whereabouts(facts)
        metres: dict[str, float] = {}
        for robot in robots if robots is not None else self.robots():
            at = where.get(robot)
            lengths = self.graph.lengths_from(self.name(at), closed) if at else {}
            for place, length in lengths.items():
                lower = place.lower()
                metres[lower] = min(length, metres.get(lower, length))
        return search_order(self.model, facts, item, metres)

    def search_shares(
        self,
        facts: FactSnapshot,
        item: str,
        robots: Sequence[str],
        closed: frozenset[str] | None = None,
        *,
        remember: bool = False,
    ) -> dict[str, str]:
        """Robot -> the place it looks for lost ``item`` at, a place of its own each,
        best first: a robot still on its way to the place it was given last (by a call
        with ``remember``) keeps it; then, of every robot and place left, the pair of the
        best fit per metre of the robot's own route (the search order's rank) is taken,
        again and again. One robot: the first place of :meth:`search_order`."""
        if closed is None:
            closed = self._closed(facts)
        weights = place_weights(self.model, facts, item)
        where, _ = whereabouts(facts)
        metres: dict[str, dict[str, float]] = {}
        for robot in robots:
            at = where.get(robot)
            lengths = self.graph.lengths_from(self.name(at), closed) if at else {}
            metres[robot] = {p.lower(): n for p, n in lengths.items() if p.lower() in weights}
        with self._lock:
            before = dict(self._looking.get(item, {}))
        shares = {r: p for r, p in before.items() if r in metres and p in metres[r]}
        pairs = sorted(
            (-weights[place] / (length + NEAR_M), robot, place)
            for robot, lengths in metres.items()
            for place, length in lengths.items()
        )
        for _, robot, place in pairs:
            if robot not in shares and place not in shares.values():
                shares[robot] = place
        if remember:
            with self._lock:
                self._looking[item] = dict(shares)
        return shares

    def _search_needs(
        self, facts: FactSnapshot, item: str, needs: _Needs, closed: frozenset[str]
    ) -> None:
        """A lost object: the places to look for it at, one per robot
        (:meth:`search_shares`, :mod:`plan_bridge.maps.search`); none left:
        :class:`ObjectNotFoundError`."""
        order = self.search_order(facts, item, needs.robots, closed)
        if not order:
            searched = [self.name(f[2]) for f in facts if f[0] == "absent" and f[1] == item]
            raise ObjectNotFoundError(self.name(item), searched)
        if len(needs.robots) > 1:
            shares = self.search_shares(facts, item, needs.robots, closed)
            needs.searches[item] = list(dict.fromkeys(shares.values())) or order[:1]
        else:
            needs.searches[item] = order[:1]
        for place in needs.searches[item]:
            needs.place(place)

    def _learn(self, facts: Collection[Fact]) -> None:
        """Objects the belief has at a place that the map does not know (seen on the way
        by a robot) join its objects: a goal may name them, a task hold them."""
        known = self._names
        for fact in facts:
            if fact[0] == "at" and len(fact) == 3 and fact[1] not in known:
                with self._lock:
                    self.model.items.setdefault(fact[1], None)
                    known[fact[1]] = fact[1]

    def _gates_needed(self, facts: FactSnapshot, closed: frozenset[str], needs: _Needs) -> None:
        """The chargers; the hallways closed but not locked, and their doorways; the
        locations of the places' spawns."""
        model = self.model
        for name in model.chargers():
            needs.place(name.lower())
        for hall in model.halls.values():
            lower = hall.name.lower()
            if hall.name in closed and ("islocked", lower) not in facts:
                needs.gates[lower] = None
                for end in hall.ends:
                    needs.place(end.lower())
        for place in list(needs.places):
            info = model.places.get(self.name(place))
            if info is not None and info.fixture is not None:
                needs.gates[info.fixture.lower()] = None

    def _goal_needs(
        self, atom: Fact, needs: _Needs, where: dict[str, str], held: dict[str, str]
    ) -> None:
        model = self.model
        name, *args = atom
        if name == "at":
            if args[0] not in needs.robots:
                needs.items[args[0]] = None
            needs.place(args[1])
        elif name == "has":
            needs.items[args[1]] = None
            needs.gates[args[0]] = None
            for place in model.spawn_places(self.name(args[0])):
                needs.place(place.lower())
        elif name == "holding":
            needs.items[args[1]] = None
        elif name == "handempty":
            item = next((i for i, robot in held.items() if robot == args[0]), None)
            if item is not None:
                needs.items[item] = None
                needs.place(self._nearest_spawn_place(where.get(args[0])))
        elif name in ("isopen", "islocked"):
            needs.gates[args[0]] = None
            for place in model.gate_places(self.name(args[0])):
                needs.place(place.lower())
        elif name == "searched":
            needs.place(args[0])

    def _nearest_spawn_place(self, start: str | None) -> str | None:
        """The place of a spawn nearest to ``start`` (where to put down what a robot
        holds)."""
        if start is None:
            return None
        lengths = self.graph.lengths_from(self.name(start))
        spawns = [
            (length, place)
            for place, length in lengths.items()
            if self.model.places[place].is_spawn
        ]
        return min(spawns)[1].lower() if spawns else None

    def _spec(
        self,
        facts: FactSnapshot,
        goal: Sequence[Fact],
        needs: _Needs,
        closed: frozenset[str],
        every_action: bool,
    ) -> ProblemSpec:
        model = self.model
        places = list(needs.places)
        objects: list[tuple[str, str]] = [(r, "bot") for r in needs.robots]
        objects += [(i, "item") for i in needs.items]
        objects += [(p, "spot") for p in places]
        objects += [(p, "spot") for p in needs.searched if p not in needs.places]
        for gate in needs.gates:
            info = model.gates.get(self.name(gate))
            if info is not None:
                objects.append((gate, info.kind))
        names = {name for name, _ in objects}
        init: set[Fact] = {f for f in facts if f[0] not in MAP_PREDICATES and _about(f, names)}
        values: dict[Fact, float] = {
            a: v
            for a, v in values_of(facts).items()
            if a[0] not in MAP_FUNCTIONS and _about(a, names)
        }
        for robot in needs.robots:
            make = model.robot(self.name(robot))
            values[("drain-per-metre", robot)] = round(make.drain, 3)
            values[("top-speed", robot)] = round(make.speed, 3)
        for index, a in enumerate(places):
            for b in places[index + 1 :]:
                route = self.graph.route(self.name(a), self.name(b), closed)
                if route is None:
                    continue
                metres = max(round(route.length, 3), _MIN_METRES)
                for first, second in ((a, b), (b, a)):
                    init.add(("route", first, second))
                    values[("metres", first, second)] = metres
        self._gate_facts(needs, init, values)
        for item, spots in needs.searches.items():
            init.update(("may-hold", spot, item) for spot in spots)
        return ProblemSpec(
            self.domain_text if every_action else self._domain_without_search,
            f"{_pddl_name(model.name)}-task",
            tuple(objects),
            tuple(sorted(init)),
            tuple(sorted(values.items())),
            tuple(goal),
            comment=f"The task plan_bridge.maps made of {model.name} for this goal.",
            search=SEARCH,
            makespan_metric=True,
            # Robots together: the shortest plan (one opens the locker while the other
            # brings the box), not the first one (one robot does everything).
            improve_s=TEAM_IMPROVE_S if len(needs.robots) > 1 else 0.0,
        )

    def _gate_facts(self, needs: _Needs, init: set[Fact], values: dict[Fact, float]) -> None:
        """Which places reach which gates, spawns and chargers; hallways' doorways."""
        model = self.model
        for place in needs.places:
            info = model.places.get(self.name(place))
            if info is None:
                continue
            for gate in info.gates:
                if gate.lower() in needs.gates:
                    init.add(("reaches-gate", place, gate.lower()))
            if info.fixture is not None and info.fixture.lower() in needs.gates:
                init.add(("spawn-of", place, info.fixture.lower()))
                if model.gates[info.fixture].is_charger:
                    init.add(("is-charger", info.fixture.lower()))
        for gate in needs.gates:
            hall = model.halls.get(self.name(gate))
            if hall is None:
                continue
            a, b = (end.lower() for end in hall.ends)
            if a in needs.places and b in needs.places and a != b:
                metres = max(round(hall.length, 3), _MIN_METRES)
                for first, second in ((a, b), (b, a)):
                    init.add(("hall-ends", first, second, gate))
                    values[("metres", first, second)] = metres


def whereabouts(facts: Iterable[Fact]) -> tuple[dict[str, str], dict[str, str]]:
    """Where the belief ``facts`` has things (robot or object -> place) and who holds
    what (object -> robot)."""
    where: dict[str, str] = {}
    held: dict[str, str] = {}
    for fact in facts:
        if fact[0] == "at" and len(fact) == 3:
            where[fact[1]] = fact[2]
        elif fact[0] == "holding" and len(fact) == 3:
            held[fact[2]] = fact[1]
    return where, held


def _static(spec: ProblemSpec) -> tuple[object, ...]:
    """What of a spec comes from the map (its task is the same when this is)."""
    facts = tuple(f for f in spec.init if f[0] in MAP_PREDICATES)
    numbers = tuple((a, v) for a, v in spec.values if a[0] in MAP_FUNCTIONS)
    return facts, numbers


def _about(atom: Fact, names: set[str]) -> bool:
    return all(arg in names for arg in atom[1:])


def _f(*words: str) -> Fact:
    return tuple(word.lower() for word in words)


def _pddl_name(text: str) -> str:
    import re

    cleaned = re.sub(r"[^A-Za-z0-9_-]", "-", text).lower()
    return cleaned if cleaned[:1].isalpha() else f"w-{cleaned}"
