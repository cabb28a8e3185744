"""Planning a fleet: goals shared out to robots, each robot planned on its own.

One temporal problem for every robot and every goal grows with their product: three
robots and three deliveries already take a temporal planner tens of seconds. The
:class:`FleetPlanner` plans as fleet managers do:

1. the goal's atoms become jobs, and the jobs go to robots by route cost on the map
   (:mod:`.jobs`);
2. each robot with jobs gets its own task (:meth:`RouteTasks.task_for
   <plan_bridge.maps.tasks.RouteTasks.task_for>` for that robot and its jobs: its
   place, its jobs' places, the chargers) and is planned by the inner planner, the
   robots' solves in parallel;
3. the robots' plans run side by side: their steps, each plan starting at time 0, make
   one timeline.

What robots share stays consistent: every object is in one job, so one robot's plan
moves it; a door one plan opens is one the others' routes do not count on (they route
over the hallways the belief holds open); a hallway found closed changes every robot's
routes at the next plan. A robot's plan that the inner planner cannot find alone (a
job that needs a second robot: a locked-in object another robot must let out) is
planned again with the nearest other robot joining in; a goal with one job is planned
with the two robots nearest to it, so a second robot can help (one opens the locker
the other brings a box to).

A replan after a failure keeps each robot's plan where it still holds: a robot with
the same jobs whose remaining steps are still valid from the belief goes on with them
(no planner call); only the others are planned again.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from plan_bridge.belief import FactSnapshot, values_of
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.task_view import project
from plan_bridge.fleet.jobs import Job, allocate, jobs_of
from plan_bridge.maps.plans import tidied
from plan_bridge.maps.tasks import RouteTasks
from plan_bridge.pddl.task import Fact, FactLike, PlanningTask, parse_fact
from plan_bridge.planning.types import (
    Planner,
    PlanResult,
    PlanStatus,
    PlanStep,
    accepts_cancel,
    snapshot_values,
)

__all__ = ["FleetPlanner"]

#: Robots planned together for a goal of one job (the nearest ones).
_HELPERS = 2
#: The planner named for a robot that kept the rest of its plan.
_KEPT = "kept"
#: Action models kept for the last tasks planned (tasks come back from the view's cache).
_MODELS_KEPT = 32


@dataclasses.dataclass
class _RobotPlan:
    """What the fleet planner remembers of one robot's last plan."""

    jobs: tuple[Job, ...]
    steps: list[PlanStep]


class FleetPlanner:
    """Plans a fleet's task robot by robot with ``inner`` (see the module's doc)."""

    def __init__(self, inner: Planner, view: RouteTasks) -> None:
        self.inner = inner
        self.view = view
        self._last: dict[str, _RobotPlan] = {}
        # The last tasks' models (a model holds its task: weak keys would never let go).
        self._models: OrderedDict[PlanningTask, ActionModel] = OrderedDict()
        self._lock = threading.Lock()

    @property
    def name(self) -> str:
        return self.inner.name

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
        cancel: threading.Event | None = None,
        values: Mapping[Fact, float] | None = None,
    ) -> PlanResult:
        started = time.monotonic()
        numbers = snapshot_values(initial_state, values)
        facts = FactSnapshot(
            task.initial_facts if initial_state is None else map(parse_fact, initial_state),
            numbers if initial_state is not None else _initial_values(task),
        )
        atoms = tuple(task.goal_facts if goal is None else (parse_fact(a) for a in goal))
        # The belief given is the task's facts: which hallways are closed is the task's.
        closed = self.view.closed_for(task)
        if closed is None:
            closed = self.view.closed_halls(facts)
        # A robot the belief given puts nowhere (left out by the caller) gets no job.
        robots = [
            r
            for r in self.view.robots()
            if r in task.objects and self.view.robot_place(facts, r) is not None
        ]
        jobs = jobs_of(atoms, robots, facts, self.view)
        if len(robots) < 2 or not jobs:
            return self._solve_one(task, facts, atoms, timeout, cancel)
        plan = _Planning(facts, closed, started + timeout, cancel, started, tuple(robots))
        split = self._search_split(task, jobs, robots, plan)
        if split is not None:
            return split
        if len(jobs) == 1:
            return self._team(self._nearest(jobs[0], robots, plan), jobs, plan)
        shares = allocate(jobs, robots, facts, self.view, closed)
        return self._shares(shares, plan)

    # -- one task, as it is ---------------------------------------------------------
    def _solve_one(
        self,
        task: PlanningTask,
        facts: FactSnapshot,
        atoms: Sequence[Fact],
        timeout: float,
        cancel: threading.Event | None,
    ) -> PlanResult:
        state = project(facts, task)
        options: dict[str, Any] = {"timeout": timeout, "initial_state": state, "goal": atoms}
        if cancel is not None and accepts_cancel(self.inner):
            options["cancel"] = cancel
        return self._tidied(self.inner.solve(task, **options), task, state)

    def _solve_part(
        self, robots: Sequence[str], jobs: Sequence[Job], plan: _Planning
    ) -> PlanResult:
        """The task of ``jobs`` for ``robots`` alone, planned by the inner planner."""
        atoms = tuple(atom for job in jobs for atom in job.atoms)
        task = self.view.task_for(plan.facts, atoms, robots=robots, closed=plan.closed)
        state = project(plan.facts, task)
        options: dict[str, Any] = {"timeout": max(plan.left(), 0.05), "initial_state": state}
        if plan.cancel is not None and accepts_cancel(self.inner):
            options["cancel"] = plan.cancel
        return self._tidied(self.inner.solve(task, **options), task, state)

    def _tidied(self, result: PlanResult, task: PlanningTask, state: FactSnapshot) -> PlanResult:
        """``result`` with its robots' successive drives merged (:mod:`plan_bridge.maps.plans`)."""
        if not result.solved:
            return result
        steps = tidied(result.actions, task, state, self._model(task))
        if len(steps) == len(result.actions):
            return result
        dropped = len(result.actions) - len(steps)
        note = f"{dropped} drive(s) to and fro merged into the drives they were part of"
        return dataclasses.replace(result, actions=steps, warnings=(*result.warnings, note))

    # -- robots together ------------------------------------------------------------
    def _nearest(self, job: Job, robots: Sequence[str], plan: _Planning) -> list[str]:
        """The robots nearest to where ``job`` begins (its own robot first)."""
        if job.robot is not None:
            others = [r for r in robots if r != job.robot]
            return [job.robot, *self._by_distance(job.start, others, plan)[: _HELPERS - 1]]
        return self._by_distance(job.start, robots, plan)[:_HELPERS]

    def _by_distance(self, place: str | None, robots: Sequence[str], plan: _Planning) -> list[str]:
        if place is None:
            return list(robots)
        lengths = self.view.graph.lengths_from(self.view.name(place), plan.closed)

        def metres(robot: str) -> float:
            at = self.view.robot_place(plan.facts, robot)
            return lengths.get(self.view.name(at), math.inf) if at else math.inf

        return sorted(robots, key=lambda r: (metres(r), r))

    def _team(self, team: Sequence[str], jobs: Sequence[Job], plan: _Planning) -> PlanResult:
        result = self._solve_part(team, jobs, plan)
        if result.solved:
            with self._lock:
                for robot in team:
                    self._last.pop(robot, None)
        return dataclasses.replace(result, planning_time_s=time.monotonic() - plan.started)

    # -- looking for a lost object, robots apart ---------------------------------------
    def _search_split(
        self,
        task: PlanningTask,
        jobs: Sequence[Job],
        robots: Sequence[str],
        plan: _Planning,
    ) -> PlanResult | None:
        """A goal whose one job to do needs a lost object (the others hold already):
        every robot looks at a place of its own at the same time
        (:meth:`RouteTasks.search_shares`: by fit per metre of its own route, a robot
        on its way keeping its place); the job goes to its robot, or to the robot of
        the best place (None: no lost object, other jobs to do, or the job's robot has
        no place or no plan alone: planned as before)."""
        lost = sorted({f[2] for f in task.initial_facts if f[0] == "may-hold"})
        if not lost:
            return None
        item = lost[0]
        mine = [j for j in jobs if any(item in atom[1:] for atom in j.atoms)]
        rest = [j for j in jobs if j not in mine]
        if len(mine) != 1 or not all(a in plan.facts for j in rest for a in j.atoms):
            return None
        job = mine[0]
        looks = self.view.search_shares(plan.facts, item, robots, plan.closed, remember=True)
        if not looks or any(place not in task.objects for place in looks.values()):
            return None  # (the task ranked the places from another belief)
        first = job.robot or next(iter(looks))
        if first not in looks:
            return None
        shares: dict[str, list[Job]] = {first: [job]}
        for robot, place in looks.items():
            if robot != first:
                shares[robot] = [Job((("at", item, place),), robot, place, place)]
        for other in rest:  # what holds keeps holding (a robot's hand stays empty)
            if other.robot in shares:
                shares[other.robot].append(other)

        def solve(robot: str) -> PlanResult:
            atoms = tuple(atom for share in shares[robot] for atom in share.atoms)
            part = self.view.task_for(
                plan.facts,
                atoms,
                robots=[robot],
                closed=plan.closed,
                search_at={item: [looks[robot]]},
            )
            # The belief holds the places of the whole fleet's search: this robot's own.
            own = [f for f in project(plan.facts, part) if f[0] != "may-hold"]
            own += [f for f in part.initial_facts if f[0] == "may-hold"]
            state = FactSnapshot(own, values_of(plan.facts))
            state = project(state, part)
            options: dict[str, Any] = {"timeout": max(plan.left(), 0.05), "initial_state": state}
            if plan.cancel is not None and accepts_cancel(self.inner):
                options["cancel"] = plan.cancel
            return self._tidied(self.inner.solve(part, **options), part, state)

        with ThreadPoolExecutor(max_workers=len(shares), thread_name_prefix="fleet") as run:
            results = dict(zip(shares, run.map(solve, shares), strict=True))
        if not results[first].solved:
            return None
        # A robot that cannot get to its place (a closed fridge it cannot open...) stays.
        kept = {r: res for r, res in results.items() if res.solved}
        return self._merged({r: shares[r] for r in kept}, kept, plan)

    # -- robots apart ----------------------------------------------------------------
    def _shares(self, shares: Mapping[str, list[Job]], plan: _Planning) -> PlanResult:
        results: dict[str, PlanResult] = {}
        todo: list[str] = []
        for robot, jobs in shares.items():
            kept = self._kept_steps(robot, tuple(jobs), plan)
            if kept is not None:
                results[robot] = PlanResult(PlanStatus.SOLVED, kept, planner=_KEPT)
            else:
                todo.append(robot)
        if todo:
            with ThreadPoolExecutor(max_workers=len(todo), thread_name_prefix="fleet") as run:
                solved = run.map(lambda r: self._solve_part([r], shares[r], plan), todo)
                results.update(zip(todo, solved, strict=True))
        for robot, result in list(results.items()):
            if not result.solved and not plan.cancelled():
                results[robot] = self._with_helper(robot, shares, plan, result)
        return self._merged(shares, results, plan)

    def _with_helper(
        self,
        robot: str,
        shares: Mapping[str, list[Job]],
        plan: _Planning,
        failed: PlanResult,
    ) -> PlanResult:
        """``robot``'s jobs planned with the nearest robot that has none (or the
        nearest robot) joining in; ``failed`` when that finds no plan either."""
        if plan.left() <= 0:
            return failed
        jobs = shares[robot]
        idle = [r for r in plan.robots if r not in shares and r != robot]
        others = idle or [r for r in plan.robots if r != robot]
        helpers = self._by_distance(jobs[0].start, others, plan)[:1]
        if not helpers:
            return failed
        result = self._solve_part([robot, *helpers], jobs, plan)
        return result if result.solved else failed

    def _kept_steps(
        self, robot: str, jobs: tuple[Job, ...], plan: _Planning
    ) -> list[PlanStep] | None:
        """The rest of ``robot``'s last plan, when it has the same jobs and the steps
        from some point on are still valid from the belief (re-timed from 0)."""
        with self._lock:
            last = self._last.get(robot)
        if last is None or last.jobs != jobs or not last.steps:
            return None
        atoms = tuple(atom for job in jobs for atom in job.atoms)
        task = self.view.task_for(plan.facts, atoms, robots=[robot], closed=plan.closed)
        model = self._model(task)
        state = project(plan.facts, task)
        for first in reversed(range(len(last.steps))):  # the shortest rest first
            rest = _from_zero(last.steps[first:])
            if all(a in task.objects for step in rest for a in step.arguments) and (
                model.check_plan(rest, state).valid
            ):
                return rest
        return None

    def _model(self, task: PlanningTask) -> ActionModel:
        with self._lock:
            model = self._models.get(task)
            if model is None:
                model = self._models[task] = ActionModel(task)
                while len(self._models) > _MODELS_KEPT:
                    self._models.popitem(last=False)
            else:
                self._models.move_to_end(task)
            return model

    def _merged(
        self,
        shares: Mapping[str, list[Job]],
        results: Mapping[str, PlanResult],
        plan: _Planning,
    ) -> PlanResult:
        elapsed = time.monotonic() - plan.started
        failed = {r: res for r, res in results.items() if not res.solved}
        if failed:
            robot, result = next(iter(failed.items()))
            jobs = "; ".join(str(job) for job in shares[robot])
            return dataclasses.replace(
                result,
                planning_time_s=elapsed,
                explanation=f"{self.view.name(robot)} has no plan for {jobs}: {result.explanation}",
            )
        steps: list[PlanStep] = []
        for robot, result in results.items():
            steps.extend(result.actions)
            with self._lock:
                self._last[robot] = _RobotPlan(tuple(shares[robot]), list(result.actions))
        if all(step.start is not None for step in steps):
            steps.sort(key=lambda s: s.start or 0.0)
        planners = sorted({r.planner for r in results.values() if r.planner != _KEPT})
        kept = sum(r.planner == _KEPT for r in results.values())
        notes = (f"{kept} of {len(results)} robots kept their plans",) if kept else ()
        return PlanResult(
            PlanStatus.SOLVED,
            steps,
            planner="+".join(planners) or _KEPT,
            planning_time_s=elapsed,
            warnings=tuple(w for r in results.values() for w in r.warnings) + notes,
            engine_time_s=sum(r.engine_time_s for r in results.values()),
        )


@dataclasses.dataclass(frozen=True)
class _Planning:
    """One solve of the fleet: the belief, the hallways to route round, the deadline."""

    facts: FactSnapshot
    closed: frozenset[str]
    deadline: float
    cancel: threading.Event | None
    started: float
    robots: tuple[str, ...] = ()
    """The robots the belief places (the others get no part)."""

    def left(self) -> float:
        return self.deadline - time.monotonic()

    def cancelled(self) -> bool:
        return self.cancel is not None and self.cancel.is_set()


def _from_zero(steps: Sequence[PlanStep]) -> list[PlanStep]:
    """``steps`` with their times moved so that the first starts at 0."""
    if not steps or any(step.start is None for step in steps):
        return list(steps)
    zero = steps[0].start or 0.0
    return [PlanStep(s.action, s.arguments, (s.start or 0.0) - zero, s.duration) for s in steps]


def _initial_values(task: PlanningTask) -> dict[Fact, float]:
    return ActionModel(task).initial_values()
