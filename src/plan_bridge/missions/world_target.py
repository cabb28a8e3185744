"""pyrobosim worlds as run targets: the generated task, the world and its skills.

:func:`load_world_target` is what :func:`~plan_bridge.missions.mission.load_target`
does for a world file (``WORLD.yaml``) or a world folder (``world.yaml``, optionally
``goals.yaml``): it loads the world, checks the goal against its names, writes the
problem of the robosim domain and loads it as the task. The target's setup gives a
:class:`~plan_bridge.robosim.world.RobosimWorld` and its skills, so
:func:`~plan_bridge.missions.runner.prepare_mission` runs it like any other target.

A world folder's variants (``plan-bridge study --variant NAME``) are its events files
(``events/NAME.yaml``), and its Python (``__init__.py``), when it has one, may define
``scripted(task, *, seed, fail_rate, variant="")``: the hand-written baseline of the
study. The skills and the world are always the robosim ones (a ``setup()`` there is
not used).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from plan_bridge.errors import PlanBridgeError
from plan_bridge.missions.mission import MissionSetup, Target, TargetError, load_domain_module
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.pddl.task import PlanningTask, load_task_from_text
from plan_bridge.robosim.events import WorldEvent, check_events, load_events
from plan_bridge.robosim.target_files import read_goals

if TYPE_CHECKING:
    from plan_bridge.planning.worker import WorkerPool
    from plan_bridge.robosim.world import RobosimWorld

__all__ = ["WorldTarget", "load_world_target", "scripted_world", "variant_events"]


@dataclass
class WorldTarget(Target):
    """A pyrobosim world with a goal (see :func:`load_world_target`)."""

    world_file: Path = Path()
    goal_text: str = ""
    goal_name: str = ""
    problem_text: str = ""
    events: list[WorldEvent] = field(default_factory=list)
    goal_names: tuple[str, ...] = ()

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
        )
        return MissionSetup(skills=robosim_skills(world), world=world)


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
    """The target of a world file or folder: the goal is ``goal``, else the folder's
    goal named ``problem`` (or its first). Raises :class:`TargetError` and
    :class:`~plan_bridge.robosim.problem.GoalError` with what is wrong and allowed."""
    from plan_bridge.robosim.loading import load_world_file
    from plan_bridge.robosim.problem import DOMAIN_PATH, describe_world, parse_goal, problem_text

    folder = target if target.is_dir() else None
    goals = read_goals(folder) if folder is not None else {}
    name = str(problem) if problem is not None and Path(problem) != world_file else ""
    if goal is None:
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
        goal = goals[name]
    sim = load_world_file(world_file)
    try:
        model = describe_world(sim, str(world_file))
        atoms = parse_goal(goal, model)
        scheduled = load_events(events) if events is not None else []
        check_events(
            scheduled,
            model.gates,
            model.items,
            [s.name for s in model.spots.values() if s.kind == "spawn"],
        )
    finally:
        for robot in sim.robots:
            robot.stop_sensor_threads()
    text = problem_text(model, atoms, name or None)
    try:
        task = load_task_from_text(
            DOMAIN_PATH.read_text(encoding="utf-8"),
            text,
            domain_name=str(DOMAIN_PATH),
            problem_name=f"{world_file} (generated)",
            prime=prime,
            before_parse=before_parse,
        )
    except PlanBridgeError as exc:
        raise TargetError(f"{world_file}: the generated problem does not load: {exc}") from exc
    label = folder.name if folder is not None else world_file.stem
    return WorldTarget(
        label,
        DOMAIN_PATH,
        world_file,
        task,
        folder,
        # A world folder's own Python (__init__.py) may give a scripted() baseline.
        load_domain_module(folder) if folder is not None else None,
        world_file=world_file,
        goal_text=goal,
        goal_name=name,
        problem_text=text,
        events=scheduled,
        goal_names=tuple(goals),
    )
