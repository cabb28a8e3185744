"""What a run target is: a :class:`Target` (a domain folder or a bare domain.pddl,
the base of :class:`~plan_bridge.missions.world_target.WorldTarget`), what a domain's
Python gives for a run (:class:`MissionSetup`, :class:`ScriptedMission`) and how that
Python is imported (:func:`load_domain_module`). Targets are loaded by
:func:`~plan_bridge.missions.mission.load_target`, whose module re-exports these names
(domain folders import them from there).
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import smach
from plan_bridge.errors import PlanBridgeError
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.execution.timed_world import TimedWorld, timed_skills
from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.skills.registry import SkillRegistry

if TYPE_CHECKING:
    from plan_bridge.belief import Belief
    from plan_bridge.execution.task_view import TaskView
    from plan_bridge.execution.world import World
    from plan_bridge.planning.types import Planner

__all__ = [
    "MissionSetup",
    "ScriptedMission",
    "Target",
    "TargetError",
    "load_domain_module",
]


class TargetError(PlanBridgeError):
    """A run target is missing, malformed, or its Python code failed to load."""


@dataclass
class MissionSetup:
    """What a domain provides for a run: skills and, optionally, more."""

    skills: SkillRegistry
    world: World | None = None
    """The world the skills act on (default: the one ``skills``' simulated skills act
    on, ``skills.world``); it learns what the user's own skills did."""
    sense: Callable[[Belief], Iterable[Any]] | None = None
    concurrent: bool = False
    """Run independent steps (e.g. of two robots) concurrently."""
    task_view: TaskView | None = None
    """Makes the task to plan from the belief (a world with a map:
    :mod:`plan_bridge.execution.task_view`); None: the target's task throughout."""
    planner_for: Callable[[Planner], Planner] | None = None
    """Wraps the planner of the run (a fleet's: one that shares the goal out to the
    robots); None: the planner as chosen."""
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass
class ScriptedMission:
    """The hand-written baseline of a domain: one SMACH machine with explicit recovery.

    ``machine.execute()`` runs the whole mission in ``world`` (no planner); success is
    judged by ``world.goal_reached()``, the same check as for planned runs.
    """

    machine: smach.State
    """A ``smach.State`` (normally a StateMachine) whose userdata is already filled."""
    world: World
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass
class Target:
    """A loaded run target."""

    name: str
    domain_path: Path
    problem_path: Path
    task: PlanningTask
    folder: Path | None = None
    module: ModuleType | None = None
    given_goal: str | None = None
    """The goal given at run time (``--goal``) in place of the problem file's, on one
    line (see :mod:`~plan_bridge.missions.given_goal`); None: the file's own."""

    @property
    def problem_label(self) -> str:
        """What a run's header says it plans: ``problem p01.pddl`` (``, goal (...)``
        with a goal given at run time)."""
        if self.given_goal is not None:
            return f"problem {self.problem_path.name}, goal {self.given_goal}"
        return f"problem {self.problem_path.name}"

    @property
    def problems(self) -> list[Path]:
        """Every problem of the folder (or just the given one)."""
        if self.folder is None:
            return [self.problem_path]
        return sorted((self.folder / "problems").glob("*.pddl"))

    @property
    def skill_map_path(self) -> Path | None:
        """The folder's ``skills.toml`` (see :mod:`plan_bridge.skills.skill_map`), if any."""
        if self.folder is None:
            return None
        from plan_bridge.skills.skill_map import find_skill_map

        return find_skill_map(self.folder)

    @property
    def has_own_skills(self) -> bool:
        """Whether the folder's Python defines ``setup()`` (its own skills and world)."""
        return self.module is not None and hasattr(self.module, "setup")

    @property
    def task_view(self) -> TaskView | None:
        """What makes the task to plan from the belief (a world with a map), for
        :attr:`MissionSetup.task_view`; None: this target's task throughout."""
        return None

    def planner_for(self, inner: Planner) -> Planner:
        """The planner of a run of this target that plans with ``inner``
        (:attr:`MissionSetup.planner_for`): ``inner`` itself."""
        return inner

    def figures(self) -> dict[str, Any]:
        """What loading the target took, for a run's report (none here)."""
        return {}

    def upkeep_goals(self, facts: Collection[Fact], values: Mapping[Fact, float]) -> list[Fact]:
        """Goal atoms a mission of orders adds for its robots' sake in the belief
        ``facts`` and ``values`` (a world with chargers: robots low on battery charge);
        none for a PDDL target, whose domain says nothing of robots' upkeep."""
        del facts, values
        return []

    def read_order_goal(self, text: str) -> list[Fact]:
        """An order's goal (atoms such as ``(at r1 lab) (holding r1 cup)``) as atoms of
        the task, checked; raises :class:`~plan_bridge.errors.PlanBridgeError` saying
        what is wrong (an unknown name, a wrong arity or type)."""
        from plan_bridge.execution.control import parse_goal

        text = text.strip()
        if text.startswith("(and ") or text.startswith("(and("):
            text = text[text.index("and") + 3 : text.rindex(")")]
        atoms = [self.task.check_fact(fact) for fact in parse_goal(text)]
        if not atoms:
            raise TargetError(f"goal {text!r}: no atoms; an order's goal is atoms like (at r1 lab)")
        return atoms

    def setup(self, *, seed: int, fail_rate: float, variant: str = "") -> MissionSetup:
        """Skills and world for one run: the domain's ``setup()`` (or symbolic skills),
        then the folder's ``skills.toml`` on top (its :class:`SkillMap` in
        ``extra["skill_map"]``). Raises :class:`SkillMapError` for a bad map."""
        result = self._domain_setup(seed=seed, fail_rate=fail_rate, variant=variant)
        path = self.skill_map_path
        if path is not None:
            from plan_bridge.skills.skill_map import load_skill_map

            skill_map = load_skill_map(path, self.task, package=self.module)
            origin = getattr(self.module, "__file__", None) or self.folder
            skill_map.apply(
                result.skills,
                registered_by=f"the domain's setup() ({origin})" if self.has_own_skills else "",
            )
            result.extra["skill_map"] = skill_map
        return result

    def _domain_setup(self, *, seed: int, fail_rate: float, variant: str) -> MissionSetup:
        factory = getattr(self.module, "setup", None) if self.module is not None else None
        if factory is None:
            if _has_durative_actions(self.task):
                # Durative actions take their time: a symbolic step's at-start effects
                # hold while it runs (required concurrency: a lamp lit during a photo).
                timed = TimedWorld(self.task, seed=seed, fail_rate=fail_rate, variant=variant)
                return MissionSetup(skills=timed_skills(timed), world=timed)
            world = SimulatedWorld(self.task, seed=seed, fail_rate=fail_rate, variant=variant)
            return MissionSetup(skills=symbolic_skills(world), world=world)
        options: dict[str, Any] = {"seed": seed, "fail_rate": fail_rate}
        if variant:
            if "variant" not in inspect.signature(factory).parameters:
                raise TargetError(f"{self.folder}: setup() does not take a world variant")
            options["variant"] = variant
        try:
            result = factory(self.task, **options)
        except PlanBridgeError:
            raise
        except Exception as exc:
            raise TargetError(f"{self.folder}: setup() raised {type(exc).__name__}: {exc}") from exc
        if not isinstance(result, MissionSetup):
            raise TargetError(
                f"{self.folder}: setup() returned {type(result).__name__}; it must return a "
                f"plan_bridge.missions.mission.MissionSetup"
            )
        return result


def _has_durative_actions(task: PlanningTask) -> bool:
    from plan_bridge.planning.engines import problem_kind

    return problem_kind(task).temporal


def load_domain_module(folder: Path) -> ModuleType | None:
    """Import the folder's Python as a package (so its modules import each other)."""
    entry = folder / "__init__.py"
    if not entry.is_file():
        entry = folder / "skills.py"
        if not entry.is_file():
            return None
    name = f"plan_bridge_domain_{folder.resolve().name}_{abs(hash(str(folder.resolve())))}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(
        name, entry, submodule_search_locations=[str(folder)]
    )
    if spec is None or spec.loader is None:
        raise TargetError(f"{entry}: cannot be imported")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:
        del sys.modules[name]
        raise TargetError(
            f"{entry}: importing the domain's Python failed: {type(exc).__name__}: {exc}"
        ) from exc
    return module
