"""Problems built in memory: data in, unified-planning's problem out (no PDDL read)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from plan_bridge.pddl.restate import replace_init
from plan_bridge.pddl.source import SourceText
from plan_bridge.pddl.spec import ProblemSpec, domain_name_of, without_actions
from plan_bridge.pddl.task import task_from_spec

DOMAIN = """
(define (domain rooms)
  (:requirements :strips :typing :numeric-fluents)
  (:types robot room)
  (:predicates (at ?r - robot ?x - room) (door ?a ?b - room))
  (:functions (metres ?a ?b - room))
  (:action go :parameters (?r - robot ?a ?b - room)
    :precondition (and (at ?r ?a) (door ?a ?b))
    :effect (and (not (at ?r ?a)) (at ?r ?b))))
"""


def spec(**changes: object) -> ProblemSpec:
    base = ProblemSpec(
        DOMAIN,
        "two-rooms",
        (("r1", "robot"), ("hall", "room"), ("lab", "room")),
        (("at", "r1", "hall"), ("door", "hall", "lab")),
        ((("metres", "hall", "lab"), 4.5),),
        (("at", "r1", "lab"),),
    )
    return base.with_state(**changes) if changes else base  # type: ignore[arg-type]


def test_a_spec_builds_the_problem_it_describes() -> None:
    task = task_from_spec(spec())
    assert task.problem_text is None and task.spec is not None and task.domain_text == DOMAIN
    assert task.objects == {"r1": "robot", "hall": "room", "lab": "room"}
    assert task.initial_facts == {("at", "r1", "hall"), ("door", "hall", "lab")}
    assert task.goal_facts == (("at", "r1", "lab"),)
    problem = task.problem
    value = problem.initial_value(
        problem.fluent("metres")(problem.object("hall"), problem.object("lab"))
    )
    assert float(value.constant_value()) == 4.5


def test_a_spec_travels_as_json_and_comes_back_the_same() -> None:
    first = spec()
    again = ProblemSpec.from_json(DOMAIN, first.to_json())
    assert again == first and again.key == first.key
    moved = first.with_state(init=[("at", "r1", "lab"), ("door", "hall", "lab")])
    assert moved.key != first.key and moved.goal == first.goal


def test_a_spec_writes_pddl_a_reader_reads_back_alike() -> None:
    from plan_bridge.pddl.task import load_task_from_text

    text = spec().pddl_text()
    assert "(:domain rooms)" in text and "(= (metres hall lab) 4.5)" in text
    task = load_task_from_text(DOMAIN, text)
    assert task.initial_facts == task_from_spec(spec()).initial_facts
    assert domain_name_of(DOMAIN) == "rooms"


def test_a_makespan_metric_is_written_and_built() -> None:
    timed = ProblemSpec(DOMAIN, "t", (("r1", "robot"),), (), (), (), makespan_metric=True)
    assert "(:metric minimize (total-time))" in timed.pddl_text()
    assert len(timed.build().quality_metrics) == 1


def test_a_new_initial_state_updates_the_spec_of_the_task() -> None:
    task = task_from_spec(spec())
    moved = task.with_initial_state(["(at r1 lab)", "(door hall lab)"])
    assert moved.spec is not None and ("at", "r1", "lab") in moved.spec.init
    assert moved.pddl_problem is not None and "(at r1 lab)" in moved.pddl_problem


def test_restating_a_problem_replaces_its_init_numbers_and_goal_and_keeps_the_rest() -> None:
    text = (
        "(define (problem p) (:domain rooms) (:objects r1 - robot hall lab - room)\n"
        "  (:init (at r1 hall) (door hall lab) (= (metres hall lab) 4) (at 5 (door lab hall)))\n"
        "  (:goal (and (at r1 lab))))"
    )
    out = replace_init(
        SourceText(text, "p.pddl", "problem"),
        [("at", "r1", "lab")],
        {("metres", "hall", "lab"): 2.5},
        [("at", "r1", "hall")],
    )
    assert "(at r1 lab)" in out and "(door hall lab)" not in out.split("(:init")[1].split(")")[0]
    assert "(= (metres hall lab) 2.5)" in out and "(= (metres hall lab) 4)" not in out
    assert "(at 5 (door lab hall))" in out  # a timed initial literal stays
    assert "(:goal (and (at r1 hall)))" in out and "(:objects r1 - robot hall lab - room)" in out


def test_an_action_left_out_of_a_domain_is_gone_and_the_rest_still_plans() -> None:
    wait = (
        "(:durative-action wait :parameters (?r - robot) :duration (= ?duration 1)\n"
        "    :condition (at start (at ?r hall)) :effect (at end (at ?r hall)))\n  "
    )
    domain = DOMAIN.replace("(:action go", wait + "(:action go")
    shorter = without_actions(domain, ["WAIT"])
    assert "wait" not in shorter and shorter.split() == DOMAIN.split()
    assert list(task_from_spec(replace(spec(), domain=shorter)).actions) == ["go"]


def test_leaving_out_an_action_the_domain_does_not_have_names_it() -> None:
    with pytest.raises(ValueError, match="no action 'fly'"):
        without_actions(DOMAIN, ["fly"])
