"""Loading PDDL into a PlanningTask, and the errors for input that cannot be loaded."""

from __future__ import annotations

import pickle
import time
from pathlib import Path

import pytest

from plan_bridge.errors import FactError, PddlError, PlannerNotFoundError, UnsupportedFeatureError
from plan_bridge.pddl.task import (
    format_fact,
    load_task,
    load_task_from_text,
    parse_fact,
    task_from_problem,
)


def test_every_parseable_bench_problem_loads(bench_problem: tuple[Path, Path]) -> None:
    domain, problem = bench_problem
    task = load_task(domain, problem)
    assert task.actions and task.objects and task.initial_facts and task.goal_facts
    assert task.goal_is_conjunctive
    assert task.domain_path == domain and task.problem_path == problem


def test_storage_either_types_give_a_located_explanation(bench: Path) -> None:
    domain = bench / "storage" / "domain.pddl"
    with pytest.raises(UnsupportedFeatureError) as caught:
        load_task(domain, bench / "storage" / "p01.pddl")
    error = caught.value
    assert error.feature == "either-types"
    assert (error.line, error.column) == (12, 16)
    message = str(error)
    assert message.startswith(f"{domain}:12:16: unsupported PDDL construct `(either")
    assert ":predicates" in message
    assert "(in ?x - (either storearea crate) ?p - place)" in message
    assert "`surface` is a supertype" in message
    assert "Traceback" not in message


def test_task_exposes_actions_predicates_objects_and_facts(doors) -> None:  # type: ignore[no-untyped-def]
    task = load_task(*doors())
    assert task.actions["unlock"].arity == 2
    assert [(p.name, p.type) for p in task.actions["unlock"].parameters] == [
        ("k", "key"),
        ("r", "room"),
    ]
    assert task.predicates["connected"].arity == 2
    assert task.objects == {"hall": "room", "kitchen": "room", "vault": "room", "k1": "key"}
    assert ("at", "hall") in task.initial_facts and ("has", "k1") in task.initial_facts
    assert task.goal_facts == (("at", "vault"),)
    assert task.objects_of_type("room") == ("hall", "kitchen", "vault")


def test_facts_parse_from_text_and_tuples() -> None:
    assert parse_fact("(At Robot  Kitchen)") == ("at", "robot", "kitchen")
    assert parse_fact(["at", "robot", "kitchen"]) == ("at", "robot", "kitchen")
    assert format_fact(("at", "robot", "kitchen")) == "(at robot kitchen)"
    with pytest.raises(FactError, match="not a ground atom"):
        parse_fact("at robot")


@pytest.mark.parametrize(
    ("fact", "message"),
    [
        ("(at attic)", "unknown object 'attic'"),
        ("(on hall)", "unknown predicate 'on'"),
        ("(at hall kitchen)", "takes 1 argument"),
        ("(at k1)", "needs type 'room'"),
    ],
)
def test_bad_facts_name_what_is_allowed(doors, fact: str, message: str) -> None:  # type: ignore[no-untyped-def]
    task = load_task(*doors())
    with pytest.raises(FactError, match=message):
        task.check_fact(fact)


def test_with_initial_state_replaces_the_initial_state_only_in_the_copy(doors) -> None:  # type: ignore[no-untyped-def]
    task = load_task(*doors())
    moved = task.with_initial_state(["(at kitchen)", ("open", "vault")])
    assert moved.initial_facts == {("at", "kitchen"), ("open", "vault")}
    assert ("at", "hall") in task.initial_facts
    values = {str(k): str(v) for k, v in moved.problem.explicit_initial_values.items()}
    assert values["at(kitchen)"] == "true" and values["at(hall)"] == "false"


def test_problem_built_in_code_becomes_a_task() -> None:
    from unified_planning.shortcuts import (
        BoolType,
        Fluent,
        InstantaneousAction,
        Not,
        Object,
        Problem,
        UserType,
    )

    location = UserType("Location")
    robot_at = Fluent("robot_at", BoolType(), where=location)
    move = InstantaneousAction("move", source=location, target=location)
    move.add_precondition(robot_at(move.parameter("source")))
    move.add_effect(robot_at(move.parameter("target")), True)
    move.add_effect(robot_at(move.parameter("source")), False)
    problem = Problem("robot")
    problem.add_fluent(robot_at, default_initial_value=False)
    problem.add_action(move)
    a, b = Object("a", location), Object("b", location)
    problem.add_objects([a, b])
    problem.set_initial_value(robot_at(a), True)
    problem.add_goal(robot_at(b))
    problem.add_goal(Not(robot_at(a)))

    task = task_from_problem(problem)
    assert task.actions["move"].parameter_names == ("source", "target")
    assert task.initial_facts == {("robot_at", "a")}
    assert task.goal_facts == (("robot_at", "b"),)
    assert not task.goal_is_conjunctive  # the negated goal is not a positive atom
    assert task.domain_path is None


def test_task_from_problem_rejects_other_objects() -> None:
    with pytest.raises(TypeError, match=r"unified_planning\.model\.Problem"):
        task_from_problem("domain.pddl")


# -- malformed input ---------------------------------------------------------------


@pytest.fixture(autouse=True)
def _doors_text(doors_text: tuple[str, str]) -> None:
    global DOORS_DOMAIN, DOORS_PROBLEM
    DOORS_DOMAIN, DOORS_PROBLEM = doors_text


DOORS_DOMAIN = ""
DOORS_PROBLEM = ""


def _load_bad_domain(tmp_path: Path, text: str | bytes, **limits: int) -> PddlError:
    domain = tmp_path / "domain.pddl"
    if isinstance(text, bytes):
        domain.write_bytes(text)
    else:
        domain.write_text(text)
    problem = tmp_path / "problem.pddl"
    problem.write_text(DOORS_PROBLEM.format(goal="(at vault)", extra=""))
    started = time.monotonic()
    with pytest.raises(PddlError) as caught:
        load_task(domain, problem, **limits)
    assert time.monotonic() - started < 5
    assert "Traceback" not in str(caught.value)
    assert str(caught.value).startswith(str(domain))
    return caught.value


def test_missing_file_is_reported_with_its_path(tmp_path: Path) -> None:
    with pytest.raises(PddlError, match="domain file not found") as caught:
        load_task(tmp_path / "nope.pddl", tmp_path / "problem.pddl")
    assert caught.value.path == str(tmp_path / "nope.pddl")


def test_truncated_file_reports_the_unclosed_parenthesis(tmp_path: Path) -> None:
    cut = DOORS_DOMAIN[: DOORS_DOMAIN.index(":effect (open")]
    error = _load_bad_domain(tmp_path, cut)
    assert "unbalanced parentheses" in error.explanation
    assert "truncated" in error.hint
    assert (error.line, error.column) == (11, 3)  # the '(:action unlock'


def test_stray_closing_parenthesis_is_located(tmp_path: Path) -> None:
    error = _load_bad_domain(
        tmp_path, DOORS_DOMAIN.replace("(:types room key)", "(:types room key))")
    )
    assert (error.line, error.column) == (4, 20)
    assert "closes the (define ...) form, but more text follows at 5:3" in error.explanation


def test_binary_garbage_is_refused(tmp_path: Path) -> None:
    error = _load_bad_domain(tmp_path, b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)))
    assert "binary data" in error.explanation


def test_non_utf8_text_is_refused_with_its_position(tmp_path: Path) -> None:
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN.encode().replace(b"doors", b"d\xe9oors", 1))
    assert "not UTF-8" in error.explanation
    assert (error.line, error.column) == (2, 18)


def test_huge_file_is_refused_before_reading(tmp_path: Path) -> None:
    padding = "; " + "x" * 98 + "\n"
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN + padding * 60_000)  # 6 MB
    assert "larger than the 5.0 MB limit" in error.explanation


def test_deep_nesting_is_refused(tmp_path: Path) -> None:
    deep = "(and " * 500 + "(at ?a)" + ")" * 500
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN.replace("(and (at ?a)", deep + " (and (at ?a)"))
    assert "nested deeper than 200" in error.explanation


def test_unknown_requirement_lists_the_allowed_ones(tmp_path: Path) -> None:
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN.replace(":typing", ":typing :teleportation"))
    assert error.explanation == "unknown PDDL requirement ':teleportation'"
    assert (error.line, error.column) == (3, 34)
    assert ":negative-preconditions" in error.hint


def test_derived_predicates_are_an_unsupported_feature(tmp_path: Path) -> None:
    error = _load_bad_domain(
        tmp_path, DOORS_DOMAIN.replace(":typing", ":typing :derived-predicates")
    )
    assert isinstance(error, UnsupportedFeatureError)
    assert error.feature == ":derived-predicates"


def test_misspelt_action_keyword_is_named_with_a_suggestion(tmp_path: Path) -> None:
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN.replace(":effect (open", ":efect (open"))
    assert error.explanation == (
        "unknown keyword ':efect' in (:action unlock ...) (did you mean :effect?)"
    )
    assert (error.line, error.column) == (14, 5)
    assert "^" in error.excerpt
    assert error.hint == "(:action NAME ...) takes :parameters, :precondition and :effect"


def test_misspelt_section_is_named_with_the_allowed_ones(tmp_path: Path) -> None:
    error = _load_bad_domain(tmp_path, DOORS_DOMAIN.replace("(:predicates", "(:predicate"))
    assert error.explanation == "unknown domain section ':predicate' (did you mean :predicates?)"
    assert error.line == 5
    assert ":constants" in error.hint and ":durative-action" in error.hint


def test_parameters_that_are_not_a_list_are_located_before_unified_planning(
    tmp_path: Path,
) -> None:
    error = _load_bad_domain(
        tmp_path, DOORS_DOMAIN.replace(":parameters (?k - key ?r - room)", ":parameters ?k")
    )
    assert error.explanation == ":parameters of unlock must be a list: (?x - type ...)"
    assert error.line is not None and 10 <= error.line <= 14
    assert error.excerpt


def test_empty_file_and_swapped_files_are_explained(tmp_path: Path) -> None:
    assert "empty" in _load_bad_domain(tmp_path, "; nothing here\n").explanation
    swapped = _load_bad_domain(tmp_path, DOORS_PROBLEM.format(goal="(at vault)", extra=""))
    assert "this is a PDDL problem file" in swapped.explanation


def test_undefined_object_in_the_problem_names_the_problem_file(tmp_path: Path) -> None:
    with pytest.raises(PddlError) as caught:
        load_task_from_text(
            DOORS_DOMAIN,
            DOORS_PROBLEM.format(goal="(at attic)", extra=""),
            problem_name="problem.pddl",
        )
    assert caught.value.path == "problem.pddl"
    assert "attic" in str(caught.value)


def test_pddl_errors_survive_pickling(bench: Path) -> None:
    with pytest.raises(UnsupportedFeatureError) as caught:
        load_task(bench / "storage" / "domain.pddl", bench / "storage" / "p01.pddl")
    copy = pickle.loads(pickle.dumps(caught.value))
    assert str(copy) == str(caught.value) and copy.feature == "either-types"


def test_before_parse_runs_after_the_cheap_checks_and_its_error_stops_the_load(
    tmp_path: Path, bench: Path
) -> None:
    calls: list[str] = []
    domain, problem = bench / "gripper" / "domain.pddl", bench / "gripper" / "prob01.pddl"
    load_task(domain, problem, before_parse=lambda: calls.append("checked"))
    assert calls == ["checked"]

    truncated = tmp_path / "domain.pddl"
    truncated.write_text("(define (domain d)")
    with pytest.raises(PddlError, match="unbalanced"):
        load_task(truncated, problem, before_parse=lambda: calls.append("checked"))
    assert calls == ["checked"]

    def refuse() -> None:
        raise PlannerNotFoundError("nope", ["fast-downward"])

    with pytest.raises(PlannerNotFoundError, match="nope"):
        load_task(domain, problem, before_parse=refuse)
