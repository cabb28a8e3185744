"""Planning through unified-planning engines in killable worker processes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import pytest

from plan_bridge.errors import FactError, PlannerNotFoundError
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import (
    Planner,
    PlanResult,
    PlanStatus,
    PlanStep,
    UPPlanner,
    get_planner,
    installed_planners,
)
from plan_bridge.planning.worker import WorkerPool


def _assert_valid_plan(task: PlanningTask, result: PlanResult) -> None:
    from unified_planning.shortcuts import PlanValidator

    assert result.status is PlanStatus.SOLVED, result.explanation
    # UP's validator warns that it "cannot establish" support for action-cost
    # problems (elevators); that warning is about UP, not about the plan.
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="We cannot establish whether")
        warnings.filterwarnings("ignore", message="The Grounder used in the")
        with PlanValidator(name="sequential_plan_validator") as validator:
            verdict = validator.validate(task.problem, task.up_plan(result.actions))
    assert verdict.status.name == "VALID", verdict


@pytest.fixture(scope="module")
def fast_downward() -> UPPlanner:
    planner = get_planner("fast-downward")
    planner.warm_up()
    return planner


@pytest.fixture(scope="module")
def pyperplan() -> UPPlanner:
    planner = get_planner("pyperplan")
    planner.warm_up()
    return planner


def test_plan_step_prints_as_a_pddl_action() -> None:
    assert str(PlanStep("pick", ("cup", "table"))) == "(pick cup table)"
    assert str(PlanStep("noop")) == "(noop)"


def test_planners_satisfy_the_planner_protocol(fast_downward: UPPlanner) -> None:
    assert isinstance(fast_downward, Planner)
    assert fast_downward.name == "fast-downward"


def test_installed_planners_include_fast_downward_and_pyperplan() -> None:
    assert {"fast-downward", "pyperplan"} <= set(installed_planners())


def test_unknown_planner_name_lists_the_installed_ones() -> None:
    with pytest.raises(PlannerNotFoundError) as caught:
        get_planner("fast-upward")
    assert caught.value.name == "fast-upward"
    assert "fast-downward" in caught.value.installed and "pyperplan" in str(caught.value)


@pytest.mark.timeout(60)
def test_every_parseable_bench_problem_solves_with_fast_downward(
    bench_problem: tuple[Path, Path], fast_downward: UPPlanner
) -> None:
    task = load_task(*bench_problem)
    result = fast_downward.solve(task, timeout=30)
    _assert_valid_plan(task, result)
    assert result.planner == "fast-downward" and result.planning_time_s > 0
    assert result.explanation == ""


@pytest.mark.parametrize(
    "name", ["gripper/prob01", "blocks/probBLOCKS-4-0", "logistics98/prob01", "miconic/s3-0"]
)
def test_small_bench_problems_solve_with_pyperplan(
    bench: Path, name: str, pyperplan: UPPlanner
) -> None:
    folder, problem = name.split("/")
    task = load_task(bench / folder / "domain.pddl", bench / folder / f"{problem}.pddl")
    _assert_valid_plan(task, pyperplan.solve(task, timeout=30))


def test_action_costs_warning_is_reported_in_the_result(
    bench: Path, fast_downward: UPPlanner
) -> None:
    folder = bench / "elevators-sat08-strips"
    result = fast_downward.solve(load_task(folder / "domain.pddl", folder / "p01.pddl"), timeout=30)
    assert result.solved
    assert any("cannot establish whether Fast Downward" in w for w in result.warnings)


def test_engine_problem_kind_mismatch_is_unsupported_with_alternatives(
    bench: Path, pyperplan: UPPlanner
) -> None:
    folder = bench / "elevators-sat08-strips"
    result = pyperplan.solve(load_task(folder / "domain.pddl", folder / "p01.pddl"), timeout=30)
    assert result.status is PlanStatus.UNSUPPORTED
    assert "ACTIONS_COST" in result.explanation and "fast-downward" in result.explanation


@pytest.mark.timeout(30)
def test_timeout_is_enforced_on_pyperplan_which_ignores_it(
    bench: Path, pyperplan: UPPlanner
) -> None:
    task = load_task(bench / "blocks" / "domain.pddl", bench / "blocks" / "probBLOCKS-14-0.pddl")
    pyperplan.solve(
        load_task(bench / "blocks" / "domain.pddl", bench / "blocks" / "probBLOCKS-4-0.pddl"),
        timeout=30,
    )
    started = time.monotonic()
    result = pyperplan.solve(task, timeout=1.0)
    elapsed = time.monotonic() - started
    assert result.status is PlanStatus.TIMEOUT
    assert elapsed < 3.0
    assert "1 s time limit" in result.explanation and "killed" in result.explanation


@pytest.mark.timeout(30)
def test_killed_worker_leaves_no_processes_behind(bench: Path) -> None:
    pool = WorkerPool(max_workers=1)
    try:
        planner = UPPlanner("pyperplan", pool=pool)
        pool.warm_up()
        with pool.worker() as worker:
            pid = worker.pid
        task = load_task(
            bench / "blocks" / "domain.pddl", bench / "blocks" / "probBLOCKS-14-0.pddl"
        )
        assert planner.solve(task, timeout=0.5).status is PlanStatus.TIMEOUT
        with pytest.raises(ProcessLookupError):
            os.killpg(pid, 0)
        # The pool replaces the killed worker transparently.
        small = load_task(
            bench / "blocks" / "domain.pddl", bench / "blocks" / "probBLOCKS-4-0.pddl"
        )
        assert planner.solve(small, timeout=30).solved
    finally:
        pool.close()


def test_unreachable_goal_is_named_by_the_relaxed_reachability_check(
    doors,
    fast_downward: UPPlanner,  # type: ignore[no-untyped-def]
) -> None:
    task = load_task(*doors(extra=""))  # nobody holds the key: the vault never opens
    result = fast_downward.solve(task, timeout=30)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.unreachable_goals == (("at", "vault"),)
    assert "goal atom (at vault) is unreachable even ignoring delete effects" in result.explanation
    assert "(open vault) never holds" in result.explanation


def test_conflicting_goals_are_unsolvable_with_the_engine_verdict(
    doors,
    pyperplan: UPPlanner,  # type: ignore[no-untyped-def]
) -> None:
    task = load_task(*doors(goal="(at vault) (at hall)"))
    result = pyperplan.solve(task, timeout=30)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.unreachable_goals == ()
    assert "pyperplan found no plan" in result.explanation
    assert "delete effects" in result.explanation


def test_replanning_from_a_given_initial_state(bench: Path, fast_downward: UPPlanner) -> None:
    folder = bench / "gripper"
    task = load_task(folder / "domain.pddl", folder / "prob01.pddl")
    belief = {f for f in task.initial_facts if f[0] != "at" or f[1] == "ball1"}
    belief |= {("at", ball, "roomb") for ball in ("ball2", "ball3", "ball4")}
    belief -= {("at-robby", "rooma")}
    belief |= {("at-robby", "roomb")}
    result = fast_downward.solve(task, timeout=30, initial_state=belief)
    assert result.solved
    assert [step.action for step in result.actions] == ["move", "pick", "move", "drop"]
    _assert_valid_plan(task.with_initial_state(belief), result)
    # The task itself is unchanged.
    assert len(fast_downward.solve(task, timeout=30).actions) == 11


def test_replanning_accepts_text_facts_and_rejects_unknown_ones(
    doors,
    fast_downward: UPPlanner,  # type: ignore[no-untyped-def]
) -> None:
    task = load_task(*doors(extra=""))
    result = fast_downward.solve(
        task,
        timeout=30,
        initial_state=["(at kitchen)", "(open vault)", "(connected kitchen vault)"],
    )
    assert result.plan_strings() == ["(move kitchen vault)"]
    with pytest.raises(FactError, match="unknown object 'attic'"):
        fast_downward.solve(task, timeout=30, initial_state=["(at attic)"])


@pytest.mark.timeout(90)
def test_concurrent_solves_from_threads_use_separate_directories(
    bench: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    pool = WorkerPool(max_workers=3)
    planner = UPPlanner("fast-downward", pool=pool)
    names = ["gripper/prob01", "blocks/probBLOCKS-6-0", "depot/p01", "gripper/prob03", "tpp/p03"]
    tasks = [load_task(bench / n.split("/")[0] / "domain.pddl", bench / f"{n}.pddl") for n in names]
    results: dict[int, PlanResult] = {}

    def solve(index: int) -> None:
        results[index] = planner.solve(tasks[index], timeout=60)

    try:
        threads = [threading.Thread(target=solve, args=(i,)) for i in range(len(tasks))]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(timeout=80)
    finally:
        pool.close()
    assert len(results) == len(tasks)
    for index, task in enumerate(tasks):
        _assert_valid_plan(task, results[index])
    assert list(tmp_path.iterdir()) == []  # no output.sas or plan files in the cwd


@pytest.mark.timeout(90)
def test_concurrent_solves_from_processes_in_one_directory(bench: Path, tmp_path: Path) -> None:
    script = (
        "import json, sys\n"
        "from plan_bridge import load_task, get_planner\n"
        "task = load_task(sys.argv[1], sys.argv[2])\n"
        "result = get_planner('fast-downward').solve(task, timeout=60)\n"
        "print(json.dumps(result.to_json()))\n"
    )
    names = ["gripper/prob03", "blocks/probBLOCKS-8-0", "logistics98/prob01"]
    processes = [
        subprocess.Popen(
            [
                sys.executable,
                "-c",
                script,
                str(bench / n.split("/")[0] / "domain.pddl"),
                str(bench / f"{n}.pddl"),
            ],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for n in names
    ]
    outputs = [p.communicate(timeout=80) for p in processes]
    for process, (out, err) in zip(processes, outputs, strict=True):
        assert process.returncode == 0, err
        payload = json.loads(out)
        assert payload["status"] == "solved" and payload["plan"]
    assert list(tmp_path.iterdir()) == []


def test_timeout_must_be_positive(doors, fast_downward: UPPlanner) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match="positive"):
        fast_downward.solve(load_task(*doors()), timeout=0)


def test_result_json_shape(doors, fast_downward: UPPlanner) -> None:  # type: ignore[no-untyped-def]
    payload = fast_downward.solve(load_task(*doors()), timeout=30).to_json()
    assert payload["status"] == "solved"
    assert payload["plan"] == [
        "(unlock k1 vault)",
        "(move hall kitchen)",
        "(move kitchen vault)",
    ] or (payload["plan_length"] == 3)
    json.dumps(payload)


def _reaches(task: PlanningTask, steps: list[PlanStep], atom: tuple[str, ...]) -> bool:
    from plan_bridge.execution.semantics import ActionModel

    model = ActionModel(task)
    state = task.initial_facts
    for step in steps:
        ground = model.ground(step)
        if not ground.applicable(state):
            return False
        state = ground.apply(state)
    return atom in state


# One problem, a different goal atom per solve: a solve that read another solve's
# output.sas or plan file would return a plan for the wrong goal.
_BLOCKS_GOALS = [("on", "d", "f"), ("on", "f", "e"), ("on", "e", "h"), ("on", "h", "c")]


@pytest.mark.timeout(120)
def test_concurrent_solves_of_one_problem_from_threads_do_not_mix_files(
    bench: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    pool = WorkerPool(max_workers=3)
    planner = UPPlanner("fast-downward", pool=pool)
    task = load_task(bench / "blocks" / "domain.pddl", bench / "blocks" / "probBLOCKS-8-0.pddl")
    jobs = [*_BLOCKS_GOALS, *_BLOCKS_GOALS]  # each goal twice: first parse, then reuse
    results: dict[int, PlanResult] = {}

    def solve(index: int) -> None:
        results[index] = planner.solve(
            task, timeout=60, initial_state=task.initial_facts, goal=[jobs[index]]
        )

    try:
        threads = [threading.Thread(target=solve, args=(i,)) for i in range(len(jobs))]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(timeout=100)
    finally:
        pool.close()
    assert len(results) == len(jobs)
    for index, atom in enumerate(jobs):
        assert results[index].solved, results[index].explanation
        assert _reaches(task, results[index].actions, atom), (atom, results[index].plan_strings())
    assert any(result.problem_reused for result in results.values())
    assert list(tmp_path.iterdir()) == []


@pytest.mark.timeout(120)
def test_concurrent_solves_of_one_problem_from_processes_in_one_directory(
    bench: Path, tmp_path: Path
) -> None:
    script = (
        "import json, sys\n"
        "from plan_bridge import load_task, get_planner\n"
        "task = load_task(sys.argv[1], sys.argv[2])\n"
        "planner = get_planner('fast-downward')\n"
        "goal = sys.argv[3:]\n"
        "plans = [planner.solve(task, timeout=60, goal=[goal]).plan_strings() for _ in range(2)]\n"
        "print(json.dumps(plans))\n"
    )
    folder = bench / "blocks"
    processes = [
        subprocess.Popen(
            [
                sys.executable,
                "-c",
                script,
                str(folder / "domain.pddl"),
                str(folder / "probBLOCKS-8-0.pddl"),
                *atom,
            ],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for atom in _BLOCKS_GOALS
    ]
    outputs = [p.communicate(timeout=110) for p in processes]
    task = load_task(folder / "domain.pddl", folder / "probBLOCKS-8-0.pddl")
    for atom, process, (out, err) in zip(_BLOCKS_GOALS, processes, outputs, strict=True):
        assert process.returncode == 0, err
        for plan in json.loads(out):
            steps = [
                PlanStep(words[0], tuple(words[1:])) for words in (s[1:-1].split() for s in plan)
            ]
            assert _reaches(task, steps, atom), (atom, plan)
    assert list(tmp_path.iterdir()) == []
