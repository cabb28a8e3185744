"""Targets of ``plan-bridge run``/``check``: a domain folder or a bare domain.pddl.

A domain folder holds ``domain.pddl``, ``problems/*.pddl`` and, optionally, Python:
an ``__init__.py`` (or ``skills.py``) defining::

    def setup(task: PlanningTask, *, seed: int, fail_rate: float) -> MissionSetup

which returns the skills (and the simulated world) of the mission, and optionally::

    def scripted(task: PlanningTask, *, seed: int, fail_rate: float) -> ScriptedMission

the same mission written by hand as one SMACH machine (the baseline). Loading a domain
folder runs its Python code, like importing a module: only run domains you trust.
Without Python, or for a bare ``domain.pddl``, every action runs as a symbolic skill
in a simulated world.
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
from plan_bridge.pddl.task import Fact, PlanningTask, load_task
from plan_bridge.skills.registry import SkillRegistry

if TYPE_CHECKING:
    from plan_bridge.belief import Belief
    from plan_bridge.execution.task_view import TaskView
    from plan_bridge.execution.world import World
    from plan_bridge.planning.types import Planner
    from plan_bridge.planning.worker import WorkerPool

__all__ = [
    "MissionSetup",
    "ScriptedMission",
    "Target",
    "TargetError",
    "load_domain_module",
    "load_target",
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


def load_target(
    target: str | Path,
    problem: str | Path | None = None,
    *,
    prime: WorkerPool | None = None,
    before_parse: Callable[[], object] | None = None,
    goal: str | None = None,
    events: str | Path | None = None,
) -> Target:
    """Load a domain folder or a domain.pddl (then ``problem`` is required), or a
    pyrobosim world (``WORLD.yaml`` or a folder with ``world.yaml``: ``goal``, or a
    goal of its goals.yaml named by ``problem``; ``events``: an events file; see
    :mod:`plan_bridge.missions.world_target`). For a PDDL target, ``goal`` replaces
    the problem's goal (see :mod:`plan_bridge.missions.given_goal`).

    ``prime`` (a planner worker pool that parses the task in parallel) and
    ``before_parse`` are those of :func:`~plan_bridge.pddl.task.load_task`.
    """
    from plan_bridge.robosim.target_files import world_file_of

    path = Path(target)
    world_file = world_file_of(path)
    if world_file is not None:
        from plan_bridge.missions.world_target import load_world_target

        return load_world_target(
            path,
            world_file,
            problem,
            goal=goal,
            events=events,
            prime=prime,
            before_parse=before_parse,
        )
    if events is not None:
        raise TargetError(
            f"{path}: --events is for pyrobosim worlds (WORLD.yaml, or a folder with "
            f"world.yaml); a PDDL target's world changes only by its actions"
        )
    if not path.exists():
        raise TargetError(
            f"{path}: no such file or folder; expected a domain folder (with domain.pddl and "
            f"problems/) or a domain .pddl file"
        )
    if path.is_dir():
        domain = path / "domain.pddl"
        if not domain.is_file():
            raise TargetError(f"{path}: a domain folder must contain domain.pddl")
        if problem is None:
            problems = sorted((path / "problems").glob("*.pddl"))
            if not problems:
                raise TargetError(f"{path}: no problems/*.pddl; give one with --problem")
            problem_path = problems[0]
        else:
            problem_path = _problem_path(Path(problem), path)
        task, given = _load_task(domain, problem_path, goal, prime, before_parse)
        module = load_domain_module(path)
        name = path.name or path.resolve().name  # `plan-bridge run .`: the folder's name
        return Target(name, domain, problem_path, task, path, module, given_goal=given)
    if problem is None:
        raise TargetError(f"{path}: a bare domain file needs --problem PROBLEM.pddl")
    problem_path = Path(problem)
    task, given = _load_task(path, problem_path, goal, prime, before_parse)
    folder_name = path.resolve().parent.name  # of `domain.pddl`, `./domain.pddl`, `../domain.pddl`
    name = folder_name if path.stem == "domain" and folder_name else path.stem
    return Target(name, path, problem_path, task, given_goal=given)


def _load_task(
    domain: Path,
    problem: Path,
    goal: str | None,
    prime: WorkerPool | None,
    before_parse: Callable[[], object] | None,
) -> tuple[PlanningTask, str | None]:
    """The task of a PDDL target, with ``goal`` (one line) in place of the file's."""
    if goal is None:
        return load_task(domain, problem, prime=prime, before_parse=before_parse), None
    from plan_bridge.missions.given_goal import load_task_with_goal

    task, given = load_task_with_goal(domain, problem, goal, prime=prime, before_parse=before_parse)
    return task, given.goal


def _problem_path(problem: Path, folder: Path) -> Path:
    """Accept a path, or a name inside the folder's problems/ (with or without .pddl)."""
    if problem.exists():
        return problem
    for candidate in (folder / "problems" / problem, folder / "problems" / f"{problem}.pddl"):
        if candidate.is_file():
            return candidate
    names = ", ".join(p.stem for p in sorted((folder / "problems").glob("*.pddl")))
    raise TargetError(f"{problem}: no such problem; problems of {folder.name}: {names or 'none'}")


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
