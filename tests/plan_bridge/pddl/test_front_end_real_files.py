"""What real (IPC) files write and the front end used to refuse, and the checks it adds
that planners do not give: a duration below zero, a numeric fluent read but never
initialised (and the planner's reason naming it)."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.errors import PddlError, UnsupportedFeatureError
from plan_bridge.pddl.front_end import FrontEnd, analyse
from plan_bridge.pddl.source import SourceText, check_source, decode_source
from plan_bridge.pddl.task import load_task_from_text

CORPUS = Path(__file__).parent / "corpus"
DOMAIN = (CORPUS / "base" / "domain.pddl").read_text()
PROBLEM = (CORPUS / "base" / "problem.pddl").read_text()
DURATIVE = (CORPUS / "base" / "durative-domain.pddl").read_text()
BATTERY = (CORPUS / "base" / "battery-domain.pddl").read_text()
DEPOT_CONSTANT = (CORPUS / "base" / "depot-constant-domain.pddl").read_text()


def _source(text: str, kind: str) -> SourceText:
    source = decode_source(text.encode(), f"{kind}.pddl", kind)
    check_source(source)
    return source


def _front(domain: str, problem: str) -> FrontEnd:
    return analyse(_source(domain, "domain"), _source(problem, "problem"))


def _durative_problem(metric: str) -> str:
    return (
        "(define (problem p) (:domain courier)\n"
        "  (:objects van - robot depot shop - place)\n"
        "  (:init (at van depot) (link depot shop))\n"
        f"  (:goal (at van shop))\n  (:metric {metric}))"
    )


# -- (:metric ... total-time) ------------------------------------------------------


@pytest.mark.parametrize("metric", ["minimize (total-time)", "MINIMIZE (TOTAL-TIME)"])
def test_the_makespan_metric_needs_no_declaration(metric: str) -> None:
    task = load_task_from_text(DURATIVE, _durative_problem(metric))
    assert [str(m) for m in task.problem.quality_metrics] == ["minimize makespan"]


def test_a_bare_total_time_is_read_as_the_makespan() -> None:
    front = _front(DURATIVE, _durative_problem("minimize total-time"))
    assert "(:metric minimize (total-time))" in front.problem_text
    task = load_task_from_text(DURATIVE, _durative_problem("minimize total-time"))
    assert [str(m) for m in task.problem.quality_metrics] == ["minimize makespan"]


@pytest.mark.parametrize(
    "metric", ["maximize (total-time)", "minimize (+ (total-time) (* 2 (total-time)))"]
)
def test_total_time_elsewhere_in_a_metric_is_unsupported_at_its_line(metric: str) -> None:
    with pytest.raises(UnsupportedFeatureError) as caught:
        _front(DURATIVE, _durative_problem(metric))
    assert caught.value.line == 5
    assert "total-time (the makespan inside a metric expression)" in caught.value.explanation
    assert "(:metric minimize (total-time))" in caught.value.explanation


def test_total_cost_in_the_metric_must_be_declared() -> None:
    problem = PROBLEM.replace(
        "(:goal (and (lies box shop))))",
        "(:goal (lies box shop))\n (:metric minimize (total-cost)))",
    )
    with pytest.raises(PddlError) as caught:
        _front(DOMAIN, problem)
    assert "undeclared function 'total-cost' in (:metric ...)" in caught.value.explanation
    assert caught.value.line == 14


# -- `?x -type` ----------------------------------------------------------------------


def test_a_dash_glued_to_its_type_is_a_dash_and_a_type_everywhere() -> None:
    domain = DEPOT_CONSTANT.replace("(:constants depot - place)", "(:constants depot -place)")
    domain = domain.replace("(link ?from - place ?to - place)", "(link ?from -place ?to -place)")
    problem = PROBLEM.replace("van - robot", "van -robot").replace("shop - place", "shop -place")
    task = load_task_from_text(domain, problem)
    assert task.objects == {"depot": "place", "van": "robot", "shop": "place", "box": "parcel"}
    assert [p.type for p in task.predicates["link"].parameters] == ["place", "place"]


def test_negative_numbers_keep_their_sign() -> None:
    source = _source(DOMAIN, "domain")
    assert [t.text for t in SourceText("(- 2 -3) (-(f)) -.5 -x", "d", "domain").tokens] == [
        "(", "-", "2", "-3", ")", "(", "-", "(", "f", ")", ")", "-.5", "-", "x",
    ]  # fmt: skip
    assert source.tokens  # the base domain still reads


# -- objects that repeat a constant ------------------------------------------------


def test_an_object_repeating_a_constant_is_a_warning_and_left_out_for_up() -> None:
    problem = PROBLEM  # its objects have `depot shop - place`, the domain `depot - place`
    front = _front(DEPOT_CONSTANT, problem)
    [warning] = front.warnings
    assert warning.startswith("problem.pddl:5:5: warning: ")
    assert "object 'depot' (line 5) is already a constant of the domain (domain.pddl:4)" in warning
    objects = front.problem_text.split("(:objects")[1].split(")")[0]
    assert "shop - place" in objects and "depot" not in objects
    task = load_task_from_text(DEPOT_CONSTANT, problem)
    assert task.objects["depot"] == "place"


def test_a_group_of_repeated_constants_leaves_with_its_type() -> None:
    problem = PROBLEM.replace("depot shop - place", "shop - place depot - place")
    front = _front(DEPOT_CONSTANT, problem)
    assert "depot - place" not in front.problem_text.split("(:objects")[1].split(")")[0]
    load_task_from_text(DEPOT_CONSTANT, problem)


def test_a_repeated_constant_of_another_type_names_both_types() -> None:
    domain = DEPOT_CONSTANT.replace(
        "(:types robot place parcel - object)", "(:types robot place parcel store - object)"
    )
    domain = domain.replace("(:constants depot - place)", "(:constants depot - place)")
    problem = PROBLEM.replace("depot shop - place", "shop - place").replace(
        "box - parcel)", "box - parcel depot - store)"
    )
    [warning] = _front(domain, problem).warnings
    assert "typed 'store' here, 'place' in the domain: the domain's type counts" in warning
    assert load_task_from_text(domain, problem).objects["depot"] == "place"


# -- (in-package ...) --------------------------------------------------------------


def test_a_lisp_preamble_is_ignored_with_a_warning_and_positions_kept() -> None:
    domain = '(in-package "PDDL")\n\n' + DOMAIN.replace(
        "(link ?from ?to))\n    :effect (and (at ?r ?to)",
        "(road ?from ?to))\n    :effect (and (at ?r ?to)",
    )
    with pytest.raises(PddlError) as caught:
        _front(domain, PROBLEM)
    assert caught.value.line == 14  # two lines further down than in DOMAIN
    front = _front('(in-package "PDDL")\n' + DOMAIN, PROBLEM)
    assert "in-package" not in front.domain_text
    assert "(in-package ...) before (define ...)" in front.warnings[0]


# -- durations ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("duration", "verdict"),
    [
        ("(= ?duration -2)", "a duration of -2"),
        ("(= ?duration (- 2))", "a duration of -2"),
        ("(= ?duration (* 4 (- 1 1.5)))", "a duration of -2"),
        ("(<= ?duration -1)", "no duration satisfies (<= ?duration -1)"),
        ("(< ?duration 0)", "no duration satisfies (< ?duration 0)"),
        ("(and (>= ?duration 1) (<= ?duration -1))", "no duration satisfies"),
    ],
)
def test_a_negative_duration_is_an_error_at_its_value(duration: str, verdict: str) -> None:
    domain = DURATIVE.replace("(= ?duration 3)", duration)
    with pytest.raises(PddlError) as caught:
        _front(domain, _durative_problem("minimize (total-time)"))
    assert verdict in caught.value.explanation
    assert caught.value.line == 7
    assert caught.value.path == "domain.pddl"


@pytest.mark.parametrize("duration", ["(>= ?duration -1)", "(<= ?duration 0)", "(= ?duration 0.5)"])
def test_durations_that_allow_a_positive_value_are_accepted(duration: str) -> None:
    domain = DURATIVE.replace("(= ?duration 3)", duration)
    front = _front(domain, _durative_problem("minimize (total-time)"))
    assert not [w for w in front.warnings if "a duration" in w or "no duration" in w]


def test_a_zero_duration_is_a_warning() -> None:
    front = _front(
        DURATIVE.replace("(= ?duration 3)", "(= ?duration 0)"),
        _durative_problem("minimize (total-time)"),
    )
    [warning] = front.warnings
    assert warning.startswith(
        "domain.pddl:7:28: warning: a duration of 0 in (:durative-action drive ...)"
    )


# -- numeric fluents read but never initialised ----------------------------------------


def _patrol(
    init: str, goal: str = "(at r1 hall)", objects: str = "r1 r2 - robot dock hall - place"
) -> str:
    return (
        "(define (problem patrol) (:domain courier)\n"
        f"  (:objects {objects})\n"
        f"  (:init (at r1 dock) (at r2 dock) (link dock hall) {init})\n"
        f"  (:goal {goal}))"
    )


def test_a_fluent_read_without_initial_value_is_named_with_both_lines() -> None:
    [warning] = _front(BATTERY, _patrol("(= (battery r2) 5)")).warnings
    assert warning.splitlines()[0] == (
        "problem.pddl:3:3: warning: battery(r1) has no initial value (problem.pddl:3); "
        "the precondition of move reads it (domain.pddl:8)"
    )
    assert "add (= (battery r1) VALUE) to (:init ...)" in warning


def test_many_missing_values_are_counted() -> None:
    objects = "r1 r2 r3 r4 r5 - robot dock hall - place"
    [warning] = _front(BATTERY, _patrol("", objects=objects)).warnings
    assert "battery(r1), battery(r2), battery(r3) and 2 more have no initial value" in warning
    assert "reads them" in warning


def test_every_value_given_no_warning() -> None:
    assert _front(BATTERY, _patrol("(= (battery r1) 1) (= (battery r2) 5)")).warnings == []


def test_a_fluent_that_is_only_assigned_is_not_read() -> None:
    domain = BATTERY.replace("(>= (battery ?r) 1)", "(at ?r ?from)").replace(
        "(decrease (battery ?r) 1)", "(assign (battery ?r) 10)"
    )
    assert _front(domain, _patrol("")).warnings == []


def test_the_goal_reads_too() -> None:
    domain = BATTERY.replace("(>= (battery ?r) 1)", "(at ?r ?from)").replace(
        "(decrease (battery ?r) 1)", "(assign (battery ?r) 10)"
    )
    [warning] = _front(domain, _patrol("(= (battery r1) 1)", goal="(> (battery r2) 2)")).warnings
    assert (
        "battery(r2) has no initial value" in warning
        and "the goal reads it (problem.pddl:4)" in warning
    )


def test_instances_a_static_precondition_or_inequality_rules_out_are_not_read() -> None:
    domain = (
        BATTERY.replace(
            "(:functions (battery ?r - robot))",
            "(:functions (battery ?r - robot) (cost ?a ?b - place))",
        )
        .replace("(>= (battery ?r) 1)", "(>= (battery ?r) (cost ?from ?to)) (not (= ?from ?to))")
        .replace(":numeric-fluents)", ":numeric-fluents :equality)")
    )
    given = "(= (battery r1) 9) (= (battery r2) 9) (= (cost dock hall) 1)"
    assert _front(domain, _patrol(given)).warnings == []  # only (link dock hall) holds
    [warning] = _front(domain, _patrol(given + " (link hall dock)")).warnings
    assert "cost(hall, dock) has no initial value" in warning


def test_a_run_that_fails_names_the_missing_value_before_the_engine(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from plan_bridge.cli import main

    domain, problem = tmp_path / "domain.pddl", tmp_path / "problem.pddl"
    domain.write_text(BATTERY)
    problem.write_text(_patrol("(= (battery r2) 5)"))
    for command in ("plan", "run"):
        assert main([command, str(domain), str(problem), "--timeout", "30"]) != 0
        captured = capsys.readouterr()
        err = captured.out + captured.err
        reason = next(
            row
            for row in err.splitlines()
            if "battery(r1) has no initial value (" in row and "warning" not in row
        )
        assert f"the precondition of move reads it ({domain}:8)" in reason
        assert "UNDEFINED_INITIAL_NUMERIC" not in reason.split("; ")[0]
