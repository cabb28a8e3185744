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

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from plan_bridge.missions.target import (
    MissionSetup,
    ScriptedMission,
    Target,
    TargetError,
    load_domain_module,
)
from plan_bridge.pddl.task import PlanningTask, load_task

if TYPE_CHECKING:
    from plan_bridge.planning.worker import WorkerPool

#: MissionSetup, ScriptedMission, Target and TargetError are defined in
#: :mod:`~plan_bridge.missions.target`; domain folders import them from here.
__all__ = [
    "MissionSetup",
    "ScriptedMission",
    "Target",
    "TargetError",
    "load_target",
]


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
