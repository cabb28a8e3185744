"""Replanning fast path: workers keep parsed problems and derive replans from them."""

from __future__ import annotations

import os
import signal
import warnings
from pathlib import Path

import pytest

import smach
from plan_bridge.execution.events import PlanComputed
from plan_bridge.execution.executive import Executive, ReplanPolicy
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import PlanningTask, load_task, task_from_problem
from plan_bridge.pddl.up_runtime import lean_copy
from plan_bridge.planning.planner import PlanResult, PlanStatus, PlanStep, UPPlanner
from plan_bridge.planning.worker import ProblemText, WorkerPool
from smach.testing import EventRecorder


def _assert_valid_plan(task: PlanningTask, result: PlanResult) -> None:
    from unified_planning.shortcuts import PlanValidator

    assert result.status is PlanStatus.SOLVED, result.explanation
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="We cannot establish whether")
        warnings.filterwarnings("ignore", message="The Grounder used in the")
        with PlanValidator(name="sequential_plan_validator") as validator:
            verdict = validator.validate(task.problem, task.up_plan(result.actions))
    assert verdict.status.name == "VALID", verdict


@pytest.fixture
def pool() -> WorkerPool:  # type: ignore[misc]
    pool = WorkerPool(max_workers=1)
    yield pool
    pool.close()


def gripper(bench: Path, problem: str = "prob01") -> PlanningTask:
    return load_task(bench / "gripper" / "domain.pddl", bench / "gripper" / f"{problem}.pddl")


def _moved(task: PlanningTask) -> frozenset[tuple[str, ...]]:
    """The gripper state after three balls were carried to roomb and the robot came back."""
    facts = {f for f in task.initial_facts if not (f[0] == "at" and f[1] != "ball1")}
    facts |= {("at", ball, "roomb") for ball in ("ball2", "ball3", "ball4")}
    return frozenset(facts)


@pytest.mark.timeout(60)
def test_a_replan_from_new_facts_reuses_the_parsed_problem(bench: Path, pool: WorkerPool) -> None:
    planner = UPPlanner("fast-downward", pool=pool)
    task = gripper(bench)
    first = planner.solve(task, timeout=30)
    assert first.solved and not first.problem_reused
    replan = planner.solve(task, timeout=30, initial_state=_moved(task))
    assert replan.problem_reused
    assert [s.action for s in replan.actions] == ["pick", "move", "drop"]
    _assert_valid_plan(task.with_initial_state(_moved(task)), replan)
    # The base problem in the worker is unchanged by the replan.
    again = planner.solve(task, timeout=30)
    assert again.problem_reused and len(again.actions) == len(first.actions) == 11


@pytest.mark.timeout(60)
def test_goal_atoms_replace_the_goal_for_one_solve(bench: Path, pool: WorkerPool) -> None:
    planner = UPPlanner("fast-downward", pool=pool)
    task = gripper(bench)
    result = planner.solve(task, timeout=30, goal=["(carry ball1 left)"])
    assert result.plan_strings() == ["(pick ball1 rooma left)"]
    both = planner.solve(task, timeout=30, initial_state=_moved(task), goal=["(at-robby roomb)"])
    assert both.problem_reused and both.plan_strings() == ["(move rooma roomb)"]
    assert len(planner.solve(task, timeout=30).actions) == 11


def test_an_unknown_goal_atom_is_a_fact_error(bench: Path, pool: WorkerPool) -> None:
    from plan_bridge.errors import FactError

    planner = UPPlanner("fast-downward", pool=pool)
    with pytest.raises(FactError, match="unknown object 'roomc'"):
        planner.solve(gripper(bench), timeout=30, goal=["(at-robby roomc)"])


@pytest.mark.timeout(60)
def test_no_plan_explanation_uses_the_replanned_goal(doors, pool: WorkerPool) -> None:  # type: ignore[no-untyped-def]
    planner = UPPlanner("fast-downward", pool=pool)
    task = load_task(*doors())
    assert planner.solve(task, timeout=30).solved
    # Without the key the vault cannot be opened: named as unreachable.
    facts = task.initial_facts - {("has", "k1")}
    result = planner.solve(task, timeout=30, initial_state=facts, goal=["(at vault)"])
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.unreachable_goals == (("at", "vault"),)


@pytest.mark.timeout(60)
def test_a_worker_that_does_not_know_the_problem_is_sent_its_text(
    bench: Path, pool: WorkerPool
) -> None:
    planner = UPPlanner("fast-downward", pool=pool)
    task = gripper(bench)
    key = ProblemText.of(task.domain_text or "", task.problem_text or "").key
    planner.warm_up()
    with pool.worker() as worker:
        worker._remember(key)  # the client wrongly believes the worker has parsed it
    result = planner.solve(task, timeout=30, initial_state=_moved(task))
    assert result.solved and not result.problem_reused
    assert planner.solve(task, timeout=30, initial_state=_moved(task)).problem_reused


@pytest.mark.timeout(60)
def test_a_replan_after_the_worker_died_starts_a_new_worker(bench: Path, pool: WorkerPool) -> None:
    planner = UPPlanner("fast-downward", pool=pool)
    task = gripper(bench)
    assert planner.solve(task, timeout=30).solved
    with pool.worker() as worker:
        os.killpg(worker.pid, signal.SIGKILL)
        worker.process.wait(timeout=10)
    result = planner.solve(task, timeout=30, initial_state=_moved(task))
    assert result.solved and not result.problem_reused
    assert [s.action for s in result.actions] == ["pick", "move", "drop"]


@pytest.mark.timeout(60)
def test_the_time_limit_holds_for_a_replan_of_a_parsed_problem(
    bench: Path, pool: WorkerPool
) -> None:
    folder = bench / "blocks"
    task = load_task(folder / "domain.pddl", folder / "probBLOCKS-14-0.pddl")
    assert UPPlanner("fast-downward", pool=pool).solve(task, timeout=30).solved
    pyperplan = UPPlanner("pyperplan", pool=pool)
    result = pyperplan.solve(task, timeout=0.5, initial_state=task.initial_facts)
    assert result.status is PlanStatus.TIMEOUT
    assert "killed" in result.explanation
    # The pool replaces the killed worker, which has to be sent the text again.
    small = pyperplan.solve(task, timeout=30, goal=["(holding a)"])
    assert small.solved and not small.problem_reused


@pytest.mark.timeout(60)
def test_a_problem_built_in_code_replans_without_rewriting_it(pool: WorkerPool) -> None:
    from unified_planning.shortcuts import (
        BoolType,
        Fluent,
        InstantaneousAction,
        Not,
        Object,
        Problem,
        UserType,
    )

    room = UserType("Room")
    at = Fluent("at", BoolType(), r=room)
    move = InstantaneousAction("move", a=room, b=room)
    move.add_precondition(at(move.parameter("a")))
    move.add_effect(at(move.parameter("a")), False)
    move.add_effect(at(move.parameter("b")), True)
    problem = Problem("rooms-in-code")
    problem.add_fluent(at, default_initial_value=False)
    problem.add_action(move)
    # "end" and "object" are PDDL keywords: the PDDL writer renames them.
    rooms = [Object(name, room) for name in ("hall", "end", "object")]
    problem.add_objects(rooms)
    problem.set_initial_value(at(rooms[0]), True)
    problem.add_goal(at(rooms[1]))
    problem.add_goal(Not(at(rooms[0])))
    task = task_from_problem(problem)
    planner = UPPlanner("fast-downward", pool=pool)
    assert planner.solve(task, timeout=30).plan_strings() == ["(move hall end)"]
    replan = planner.solve(task, timeout=30, initial_state=[("at", "object")])
    assert replan.problem_reused
    assert replan.plan_strings() == ["(move object end)"]
    sub = planner.solve(task, timeout=30, goal=[("at", "object")])
    assert sub.plan_strings() == ["(move hall object)"]


def test_lean_copy_writes_the_same_pddl_as_the_original(bench: Path) -> None:
    from unified_planning.io import PDDLWriter

    for folder, problem in (("gripper", "prob01"), ("elevators-sat08-strips", "p01")):
        task = load_task(bench / folder / "domain.pddl", bench / folder / f"{problem}.pddl")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            original = PDDLWriter(task.problem.clone()).get_problem()
            lean = PDDLWriter(lean_copy(task.problem)).get_problem()
        assert sorted(original.split("\n")) == sorted(lean.split("\n"))
        assert lean_copy(task.problem).kind == task.problem.kind


def _gripper_with_a_slip(
    task: PlanningTask, policy: ReplanPolicy | None = None, *, always: bool = False
) -> tuple[Executive, list[PlanComputed]]:
    """An executive whose first (``always``: every) ``move rooma roomb`` ends with the
    robot back in rooma."""
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    slipped: list[bool] = []

    class SlippingMove(smach.State):
        def __init__(self, *args: str) -> None:
            super().__init__(
                outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
            )
            self.args = args

        def execute(self, ud: smach.UserData) -> str:
            ok, observations = world.perform(PlanStep("move", self.args))
            if (always or not slipped) and self.args == ("rooma", "roomb"):
                slipped.append(True)
                with world._lock:
                    world._facts -= {("at-robby", "roomb")}
                    world._facts |= {("at-robby", "rooma")}
                observations = [
                    (("at-robby", "roomb"), False),
                    (("at-robby", "rooma"), True),
                ]
            ud.observations = observations
            return "succeeded" if ok else "aborted"

    skills.add("move", SlippingMove)
    return Executive(task, skills, "fast-downward", policy=policy), []


@pytest.mark.timeout(60)
def test_executive_repair_plans_only_the_missing_prefix(bench: Path) -> None:
    task = gripper(bench)
    executive, plans = _gripper_with_a_slip(task, ReplanPolicy(redo_window=0))
    executive.add_listener(lambda e: plans.append(e) if isinstance(e, PlanComputed) else None)
    assert executive.execute() == "succeeded"
    assert executive.report.repairs == 1, executive.report.decisions
    repair = next(p for p in plans if p.reason.startswith("repair"))
    assert repair.steps == ("(move rooma roomb)",)
    assert executive.report.goal_reached


@pytest.mark.timeout(60)
def test_a_step_the_world_undid_is_redone_without_a_planner_call(bench: Path) -> None:
    task = gripper(bench)
    executive, plans = _gripper_with_a_slip(task)
    executive.add_listener(lambda e: plans.append(e) if isinstance(e, PlanComputed) else None)
    assert executive.execute() == "succeeded"
    report = executive.report
    assert report.repairs == 1 and report.repair_attempts == 0
    assert report.planner_calls == 1 and len(plans) == 1
    repair = next(d for d in report.decisions if d["decision"] == "repair")
    assert "re-doing (move rooma roomb)" in repair["reason"]
    assert len(report.executed) == 11 + 1  # the 11-step plan and the re-done move


@pytest.mark.timeout(60)
def test_a_step_the_world_always_undoes_ends_the_mission_when_the_budget_is_spent(
    bench: Path,
) -> None:
    task = gripper(bench)
    executive, _ = _gripper_with_a_slip(task, ReplanPolicy(max_replans=3), always=True)
    assert executive.execute() == "aborted"
    report = executive.report
    assert report.explanation.startswith("replanning budget exhausted (3 replans)")
    redone = [d for d in report.decisions if d["decision"] == "repair"]
    assert len(redone) == 3  # three plans adopted after the first, then no more
    assert report.decisions[-1]["decision"] == "replan"


@pytest.mark.timeout(60)
def test_replan_only_policy_replans_from_the_belief_after_one_failure(bench: Path) -> None:
    task = gripper(bench)
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    failed: list[bool] = []
    executive = Executive(task, skills, "fast-downward", policy=ReplanPolicy.named("replan-only"))
    original = world.perform

    def perform_failing_once(step: PlanStep):  # type: ignore[no-untyped-def]
        if not failed and step.action == "drop":
            failed.append(True)
            return False, []
        return original(step)

    world.perform = perform_failing_once  # type: ignore[method-assign]
    plans: list[PlanComputed] = []
    executive.add_listener(lambda e: plans.append(e) if isinstance(e, PlanComputed) else None)
    assert executive.execute() == "succeeded"
    assert executive.report.replans == 1 and executive.report.planner_calls == 2
    assert plans[1].reason.startswith("replan")


# -- the recovery ladder: held plans, plan reuse, replan deadlines ---------------------------

ROOMS = Path(__file__).parents[1] / "data" / "rooms"


class FirstPlanOnly:
    """A planner that plans once (through Fast Downward), then answers every later
    solve with ``status`` (a replan that times out, or errs), recording timeouts."""

    def __init__(self, status: PlanStatus = PlanStatus.TIMEOUT) -> None:
        self.inner = UPPlanner("fast-downward")
        self.status = status
        self.timeouts: list[float] = []

    @property
    def name(self) -> str:
        return "first-plan-only"

    def solve(self, task: PlanningTask, *, timeout: float, **kwargs: object) -> PlanResult:
        self.timeouts.append(timeout)
        if len(self.timeouts) == 1:
            return self.inner.solve(task, timeout=timeout, **kwargs)  # type: ignore[arg-type]
        return PlanResult(
            self.status,
            planner=self.name,
            planning_time_s=0.01,
            explanation=f"no plan within the {timeout:g} s limit",
        )


def _failing(world: SimulatedWorld, action: str, times: int) -> list[PlanStep]:
    """Make the first ``times`` tries of ``action`` fail without an effect."""
    original = world.perform
    failed: list[PlanStep] = []

    def perform(step: PlanStep):  # type: ignore[no-untyped-def]
        if step.action == action and len(failed) < times:
            failed.append(step)
            return False, []
        return original(step)

    world.perform = perform  # type: ignore[method-assign]
    return failed


#: Retries of the default policy: one failure more sends the step to the planner.
RETRIES = ReplanPolicy().max_step_retries


def _rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


@pytest.mark.timeout(60)
def test_a_replan_that_times_out_goes_on_with_the_held_plan_to_the_goal() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    failed = _failing(world, "pick", RETRIES + 1)
    planner = FirstPlanOnly(PlanStatus.TIMEOUT)
    executive = Executive(task, symbolic_skills(world), planner)
    assert executive.execute() == "succeeded"
    report = executive.report
    assert len(failed) == RETRIES + 1 and report.retries == RETRIES
    assert report.replans == 1 and report.holds == 1
    assert report.goal_reached and world.goal_reached()
    hold = next(d for d in report.decisions if d["decision"] == "hold")
    assert hold["reason"].startswith("no plan (timeout)") and "still valid" in hold["reason"]
    assert hold["step"] == "(pick robot1 cup kitchen)"


@pytest.mark.timeout(60)
def test_without_holding_the_same_timeout_aborts_the_mission() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    _failing(world, "pick", RETRIES + 1)
    policy = ReplanPolicy(hold_valid_plan=False)
    executive = Executive(task, symbolic_skills(world), FirstPlanOnly(), policy=policy)
    assert executive.execute() == "aborted"
    assert executive.report.explanation.startswith("no plan (timeout)")


@pytest.mark.timeout(60)
def test_a_failed_replan_is_not_held_when_the_held_plan_broke() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    original = world.perform

    def perform(step: PlanStep):  # type: ignore[no-untyped-def]
        if step.action == "pick":
            # The cup is gone: the rest of the plan cannot work any more.
            with world._lock:
                world._facts.discard(("item-at", "cup", "kitchen"))
            return False, [(("item-at", "cup", "kitchen"), False)]
        return original(step)

    world.perform = perform  # type: ignore[method-assign]
    executive = Executive(task, symbolic_skills(world), FirstPlanOnly(PlanStatus.ERROR))
    assert executive.execute() == "aborted"
    assert executive.report.holds == 0
    assert executive.report.explanation.startswith("no plan (error)")


@pytest.mark.timeout(60)
def test_a_replan_gets_its_own_deadline() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    _failing(world, "pick", RETRIES + 1)
    planner = FirstPlanOnly()
    policy = ReplanPolicy(planner_timeout=40.0, replan_timeout=7.5)
    executive = Executive(task, symbolic_skills(world), planner, policy=policy)
    assert executive.execute() == "succeeded"
    assert planner.timeouts == [40.0, 7.5]


@pytest.mark.timeout(60)
def test_retries_go_on_while_the_held_plan_is_valid_without_calling_the_planner() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    _failing(world, "pick", RETRIES)
    planner = FirstPlanOnly()
    executive = Executive(task, symbolic_skills(world), planner)
    assert executive.execute() == "succeeded"
    assert executive.report.retries == RETRIES
    assert executive.report.planner_calls == 1 and executive.report.replans == 0


@pytest.mark.timeout(60)
def test_a_shared_plan_cache_reuses_the_plan_of_an_identical_state_and_goal() -> None:
    from plan_bridge.execution.plan_cache import PlanCache

    cache = PlanCache()
    reports = []
    for _ in range(2):
        task = _rooms()  # loaded again: same text, a new task object
        world = SimulatedWorld(task)
        executive = Executive(task, symbolic_skills(world), "fast-downward", plan_cache=cache)
        recorder = EventRecorder()
        executive.add_listener(recorder)
        assert executive.execute() == "succeeded"
        plans = [e for e in recorder.events if isinstance(e, PlanComputed)]
        reports.append((executive.report, plans))
    (first, _), (second, plans) = reports
    assert first.planner_calls == 1 and first.plans_reused == 0
    assert second.planner_calls == 0 and second.plans_reused == 1
    assert second.final_plan == first.final_plan
    assert "plan reused" in plans[0].reason and second.planning_time_s == 0.0
    assert cache.hits == 1


@pytest.mark.timeout(60)
def test_the_json_report_counts_planner_calls_reuses_and_holds() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    _failing(world, "pick", RETRIES + 1)
    executive = Executive(task, symbolic_skills(world), FirstPlanOnly())
    executive.execute()
    data = executive.report.to_json()
    assert {k: data[k] for k in ("planner_calls", "replans", "holds", "plans_reused")} == {
        "planner_calls": 2,
        "replans": 1,
        "holds": 1,
        "plans_reused": 0,
    }
    assert data["planners_won"] == {"fast-downward": 1}


def test_policies_refuse_bad_budgets_and_unknown_configurations() -> None:
    with pytest.raises(ValueError, match="replan_timeout must be > 0"):
        ReplanPolicy(replan_timeout=0)
    with pytest.raises(ValueError, match="unknown configuration"):
        ReplanPolicy(replan_portfolio=("fastest",))


@pytest.mark.timeout(120)
def test_run_json_reports_planner_calls_replans_repairs_holds_and_reuses(
    bench: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from plan_bridge.cli import main

    folder = bench / "blocks"
    argv = ["run", str(folder / "domain.pddl"), "--problem", str(folder / "probBLOCKS-8-0.pddl")]
    assert main([*argv, "--fail-rate", "0.3", "--seed", "3", "--json", "--quiet"]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("planner_calls", "replans", "repairs", "retries", "holds", "plans_reused"):
        assert isinstance(data[key], int), key
    assert data["planner_calls"] >= 1 and data["retries"] >= 1
    assert 1 <= sum(data["planners_won"].values()) <= data["planner_calls"]


class _Pick(smach.State):
    """A pick skill that performs the action in the world, or fails if ``broken``."""

    def __init__(self, world: SimulatedWorld, args: tuple[str, ...], broken: bool) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.world, self.args, self.broken = world, args, broken

    def execute(self, ud: smach.UserData) -> str:
        if self.broken:
            ud.observations = []
            return "aborted"
        ok, ud.observations = self.world.perform(PlanStep("pick", self.args))
        return "succeeded" if ok else "aborted"


@pytest.mark.timeout(60)
def test_a_skill_that_keeps_failing_is_replaced_by_its_variant_without_planning() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    skills.add("pick", lambda *args: _Pick(world, args, broken=True))
    skills.register("pick", variant="careful")(lambda *args: _Pick(world, args, broken=False))
    assert skills.variants("pick") == ("careful",)
    assert skills.check(task) == []
    executive = Executive(task, skills, FirstPlanOnly())
    assert executive.execute() == "succeeded"
    report = executive.report
    assert report.retries == RETRIES and report.variants_tried == 1
    assert report.planner_calls == 1 and report.replans == 0
    variant = next(d for d in report.decisions if d["decision"] == "variant")
    assert "'careful'" in variant["reason"] and variant["step"] == "(pick robot1 cup kitchen)"


def test_an_unknown_skill_variant_is_named_with_the_registered_ones() -> None:
    from plan_bridge.skills.registry import SkillError, SkillRegistry

    skills = SkillRegistry()
    skills.register("pick", variant="careful")(lambda *args: smach.State(["succeeded"]))
    with pytest.raises(SkillError, match=r"no variant 'quick'.*variants: careful"):
        skills.create(PlanStep("pick", ("robot1", "cup", "kitchen")), "quick")
    with pytest.raises(SkillError, match="already registered"):
        skills.register("pick", variant="careful")(lambda *args: smach.State(["succeeded"]))


@pytest.mark.timeout(60)
def test_a_state_the_planner_failed_from_is_not_planned_from_again() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    # Two rounds of retries, replan and hold, then success.
    _failing(world, "pick", 2 * (RETRIES + 1))
    planner = FirstPlanOnly()
    executive = Executive(task, symbolic_skills(world), planner)
    assert executive.execute() == "succeeded"
    report = executive.report
    assert report.replans == 2 and report.holds == 2
    assert report.planner_calls == 2  # the second replan knew the answer
    assert len(planner.timeouts) == 2


@pytest.mark.timeout(60)
def test_a_failed_step_whose_effects_came_true_anyway_is_skipped_without_a_planner_call() -> None:
    task = _rooms()
    world = SimulatedWorld(task)
    original = world.perform
    done: list[PlanStep] = []

    def perform(step: PlanStep):  # type: ignore[no-untyped-def]
        ok, observations = original(step)
        if step.action == "pick" and not done:
            # The skill reports a failure, yet the world changed as the step said it
            # would (somebody else did it): the rest of the plan is valid from there.
            done.append(step)
            return False, observations
        return ok, observations

    world.perform = perform  # type: ignore[method-assign]
    planner = FirstPlanOnly()
    executive = Executive(task, symbolic_skills(world), planner)
    assert executive.execute() == "succeeded"
    report = executive.report
    assert done and report.continues == 1 and report.retries == 0
    assert report.planner_calls == 1 and report.replans == 0
    assert report.goal_reached and world.goal_reached()
    skipped = next(d for d in report.decisions if d["decision"] == "continue")
    assert skipped["step"] == str(done[0]) and "still valid" in skipped["reason"]
