"""pyrobosim worlds as run targets: the generated task, the world and its skills.

:func:`load_world_target` is what :func:`~plan_bridge.missions.mission.load_target`
does for a world file (``WORLD.yaml``) or a world folder (``world.yaml``, optionally
``goals.yaml``): it loads the world once, reads its map, checks the goal against its
names, and makes the first task of the map domain in memory
(:class:`~plan_bridge.maps.tasks.RouteTasks`: the places the goal needs and routes
between them; no PDDL text is parsed). The target's setup gives a
:class:`~plan_bridge.robosim.world.RobosimWorld` (the first one on the world just
loaded), its skills and the task view, so
:func:`~plan_bridge.missions.runner.prepare_mission` runs it like any other target.

A world folder's variants (``plan-bridge study --variant NAME``) are its events files
(``events/NAME.yaml``), and its Python (``__init__.py``), when it has one, may define
``scripted(task, *, seed, fail_rate, variant="")``: the hand-written baseline of the
study. The skills and the world are always the robosim ones (a ``setup()`` there is
not used).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.fleet.planner import FleetPlanner
from plan_bridge.missions.target import MissionSetup, Target, TargetError, load_domain_module
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.robosim.events import WorldEvent, check_events, load_events
from plan_bridge.robosim.target_files import read_goals

if TYPE_CHECKING:
    from plan_bridge.maps.model import WorldModel
    from plan_bridge.maps.tasks import RouteTasks
    from plan_bridge.planning.types import Planner
    from plan_bridge.planning.worker import WorkerPool
    from plan_bridge.robosim.world import RobosimWorld

__all__ = [
    "LOW_BATTERY",
    "WorldTarget",
    "load_world_target",
    "scripted_world",
    "variant_events",
]

LOW_BATTERY = 40.0
"""Battery (percent) under which a robot of a mission of orders goes to charge: enough
for its orders in hand and the drive to a charger in buildings of tens of rooms at
pyrobosim's default drain."""


@dataclass
class WorldTarget(Target):
    """A pyrobosim world with a goal (see :func:`load_world_target`)."""

    world_file: Path = Path()
    goal_text: str = ""
    goal_name: str = ""
    problem_text: str = ""
    events: list[WorldEvent] = field(default_factory=list)
    goal_names: tuple[str, ...] = ()
    view: RouteTasks | None = None
    """The task view of the world's map (every run of the target shares it)."""
    load_s: float = 0.0
    """Seconds pyrobosim took to load the world file (its own cost)."""
    task_s: float = 0.0
    """Seconds reading the world's map and making the first task took (ours)."""
    _loaded: list[tuple[object, WorldModel]] = field(default_factory=list, repr=False)

    @property
    def problems(self) -> list[Path]:
        return [Path(name) for name in self.goal_names] or [self.world_file]

    @property
    def problem_label(self) -> str:
        """``goal fetch_soda`` (a goal of goals.yaml) or ``goal (At apple0 table0)``."""
        return f"goal {self.goal_name or self.goal_text}"

    @property
    def skill_map_path(self) -> Path | None:
        return None

    @property
    def has_own_skills(self) -> bool:
        return True

    def setup(self, *, seed: int, fail_rate: float, variant: str = "") -> MissionSetup:
        from plan_bridge.robosim.skills import robosim_skills
        from plan_bridge.robosim.world import RobosimWorld

        world = RobosimWorld(
            self.world_file,
            self.task.goal_facts,
            seed=seed,
            fail_rate=fail_rate,
            events=[*self.events, *variant_events(self.folder or self.world_file, variant)],
            # The first run acts on the world loaded for the task (pyrobosim's load is
            # its slowest part); later runs load their own.
            loaded=self._loaded.pop() if self._loaded else None,
        )
        return MissionSetup(
            skills=robosim_skills(world),
            world=world,
            task_view=self.view,
            planner_for=self.planner_for,
        )

    @property
    def task_view(self) -> RouteTasks | None:
        return self.view

    def robots(self) -> list[str]:
        """The world's robots, by their lower-case (PDDL) names (of its map)."""
        return self.view.robots() if self.view is not None else []

    def planner_for(self, inner: Planner) -> Planner:
        """A fleet planner over ``inner`` (with one robot it plans as ``inner``)."""
        return inner if self.view is None else FleetPlanner(inner, self.view)

    def figures(self) -> dict[str, Any]:
        """pyrobosim's load of the world file, and ours: its map and first task."""
        return {"world_load_s": round(self.load_s, 3), "task_s": round(self.task_s, 3)}

    def upkeep_goals(self, facts: Collection[Fact], values: Mapping[Fact, float]) -> list[Fact]:
        """``(charged ROBOT)`` for every robot below :data:`LOW_BATTERY` percent, when the
        world has a charger: its plan then ends at a charger, charged, whatever orders
        it serves first (so that no plan strands a robot with a flat battery)."""
        del facts
        if self.view is None or not self.view.model.chargers():
            return []
        return [
            ("charged", robot)
            for robot in self.view.robots()
            if values.get(("battery-level", robot), 100.0) < LOW_BATTERY
        ]

    def read_order_goal(self, text: str) -> list[Fact]:
        """An order's goal: a goal's name of the folder's goals.yaml, or atoms in
        pyrobosim's vocabulary (:func:`~plan_bridge.maps.goals.parse_goal`)."""
        from plan_bridge.maps.goals import parse_goal

        word = text.strip()
        if _GOAL_NAME.match(word):
            goals = read_goals(self.folder) if self.folder is not None else {}
            text = _named_goal(word, self.folder, goals)
        if self.view is None:
            raise TargetError(f"{self.world_file}: the world's map was not read")
        return parse_goal(text, self.view.model)


def variant_events(folder: Path, variant: str) -> list[WorldEvent]:
    """The events of a world variant: ``events/VARIANT.yaml`` of the world folder (none
    for ``""``). A study's ``--variant close_hallway`` runs the world with those events."""
    if not variant:
        return []
    events = folder / "events"
    file = events / f"{variant}.yaml"
    if not folder.is_dir() or not file.is_file():
        names = sorted(p.stem for p in events.glob("*.yaml")) if events.is_dir() else []
        hint = did_you_mean(variant, names)
        raise TargetError(
            f"{folder}: no world variant {variant!r}{hint}; the variants of a pyrobosim world "
            f"folder are its events/NAME.yaml files: {', '.join(names) or 'none'}"
        )
    return load_events(file)


def scripted_world(
    folder: Path, task: PlanningTask, *, seed: int, fail_rate: float, variant: str = ""
) -> RobosimWorld:
    """The world of one run of a world folder's scripted baseline: its ``world.yaml``
    with the task's goal, the run's seed and fail rate, and the variant's events."""
    from plan_bridge.robosim.world import RobosimWorld

    return RobosimWorld(
        folder / "world.yaml",
        task.goal_facts,
        seed=seed,
        fail_rate=fail_rate,
        events=variant_events(folder, variant),
    )


def load_world_target(
    target: Path,
    world_file: Path,
    problem: str | Path | None = None,
    *,
    goal: str | None = None,
    events: str | Path | None = None,
    prime: WorkerPool | None = None,
    before_parse: Callable[[], object] | None = None,
) -> WorldTarget:
    """The target of a world file or folder: the goal is ``goal`` (atoms, or the name
    of a goal of the folder's goals.yaml), else the folder's goal named ``problem`` (or
    its first). Raises :class:`TargetError` and
    :class:`~plan_bridge.maps.goals.GoalError` with what is wrong and allowed."""
    import time

    from plan_bridge.maps.goals import parse_goal
    from plan_bridge.maps.tasks import RouteTasks
    from plan_bridge.robosim.description import describe_world
    from plan_bridge.robosim.loading import load_world_file

    folder = target if target.is_dir() else None
    goals = read_goals(folder) if folder is not None else {}
    name, goal = _goal_of(target, world_file, folder, goals, problem, goal)
    if prime is not None:
        # Planner processes start while pyrobosim loads the world: two for a fleet,
        # whose robots are planned side by side.
        prime.warm_up(2 if _robots_in(world_file) > 1 else 1)
    started = time.perf_counter()
    sim = load_world_file(world_file)
    load_s = time.perf_counter() - started
    started = time.perf_counter()
    model = describe_world(sim, str(world_file))
    atoms = parse_goal(goal, model)
    scheduled = load_events(events) if events is not None else []
    check_events(
        scheduled,
        model.gates,
        model.items,
        [spawn for gate in model.gates.values() for spawn in gate.spawns],
    )
    if before_parse is not None:
        before_parse()
    view = RouteTasks(model)
    try:
        task = view.task_for(view.belief(), atoms, every_action=True)
    except PlanBridgeError as exc:
        raise TargetError(f"{world_file}: no task for the goal: {exc}") from exc
    if prime is not None:
        from plan_bridge.planning.problem_source import problem_source

        prime.prime(problem_source(task).text)
    task_s = time.perf_counter() - started
    label = folder.name if folder is not None else world_file.stem
    spec = task.spec
    return WorldTarget(
        label,
        view.domain_path,
        world_file,
        task,
        folder,
        # A world folder's own Python (__init__.py) may give a scripted() baseline.
        load_domain_module(folder) if folder is not None else None,
        world_file=world_file,
        goal_text=goal,
        goal_name=name,
        problem_text=spec.pddl_text() if spec is not None else "",
        events=scheduled,
        goal_names=tuple(goals),
        view=view,
        load_s=load_s,
        task_s=task_s,
        _loaded=[(sim, model)],
    )


_GOAL_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


def _robots_in(world_file: Path) -> int:
    """How many robots a world file lists (0 when it cannot tell: loading says why)."""
    import yaml

    try:
        data = yaml.safe_load(world_file.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError):
        return 0
    robots = data.get("robots") if isinstance(data, dict) else None
    return len(robots) if isinstance(robots, list) else 0


def _named_goal(word: str, folder: Path | None, goals: dict[str, str], said: str = "") -> str:
    """The atoms of the goal named ``word`` (raises :class:`TargetError` naming the
    goals there are)."""
    if word in goals:
        return goals[word]
    known = f"; goals of {folder}/goals.yaml: {', '.join(goals)}" if goals else ""
    raise TargetError(
        f"{said}{word}: not a goal atom such as (At apple0 table0_tabletop), nor the name of "
        f"a goal{did_you_mean(word, goals)}{known}"
    )


def _goal_of(
    target: Path,
    world_file: Path,
    folder: Path | None,
    goals: dict[str, str],
    problem: str | Path | None,
    goal: str | None,
) -> tuple[str, str]:
    """(the goal's name or "", its atoms' text) of what was asked for: ``goal``, a
    name of goals.yaml given as ``goal`` or ``problem``, or the first of goals.yaml."""
    name = str(problem) if problem is not None and Path(problem) != world_file else ""
    if goal is not None and _GOAL_NAME.match(goal.strip()):
        word = goal.strip()
        return word, _named_goal(word, folder, goals, "--goal ")
    if goal is not None:
        return Path(name).name if name else "", goal
    if not goals:
        raise TargetError(
            f'{target}: give the goal with --goal, e.g. --goal "(At apple0 table0_tabletop)" '
            f"(a world folder may list named goals in goals.yaml)"
        )
    if name and Path(name).name not in goals:
        hint = did_you_mean(Path(name).name, goals)
        raise TargetError(
            f"{name}: no such goal in {folder}/goals.yaml{hint}; goals: {', '.join(goals)}"
        )
    name = Path(name).name if name else next(iter(goals))
    return name, goals[name]
