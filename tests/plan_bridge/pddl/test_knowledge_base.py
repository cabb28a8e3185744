"""The knowledge base: a problem under construction, checked against its domain."""

from __future__ import annotations

import re
import threading
from pathlib import Path

import pytest

from plan_bridge.errors import FactError, PddlError
from plan_bridge.pddl.knowledge import (
    KnowledgeBase,
    KnowledgeChange,
    KnowledgeError,
    function_atom,
    goal_atoms,
    value_assignments,
)
from plan_bridge.pddl.knowledge_terms import initial_values
from plan_bridge.pddl.task import load_task_from_text
from plan_bridge.planning.planner import get_planner

pytestmark = pytest.mark.timeout(120)

PARCELS = """\
; Trucks carry parcels along roads; the depot is a place of every problem.
(define (domain parcels)
  (:requirements :strips :typing)
  (:types vehicle place parcel - object truck - vehicle)
  (:constants depot - place)
  (:predicates (at ?v - vehicle ?p - place) (road ?a ?b - place)
               (parcel-at ?x - parcel ?p - place) (loaded ?x - parcel ?v - vehicle))
  (:action drive
    :parameters (?v - vehicle ?a ?b - place)
    :precondition (and (at ?v ?a) (road ?a ?b))
    :effect (and (at ?v ?b) (not (at ?v ?a))))
  (:action load
    :parameters (?x - parcel ?v - vehicle ?p - place)
    :precondition (and (at ?v ?p) (parcel-at ?x ?p))
    :effect (and (loaded ?x ?v) (not (parcel-at ?x ?p))))
  (:action unload
    :parameters (?x - parcel ?v - vehicle ?p - place)
    :precondition (and (at ?v ?p) (loaded ?x ?v))
    :effect (and (parcel-at ?x ?p) (not (loaded ?x ?v)))))
"""

CHARGING = """\
; Robots dock to charge; docking costs one.
(define (domain charging)
  (:requirements :strips :typing :numeric-fluents :action-costs)
  (:types robot dock)
  (:predicates (docked ?r - robot ?d - dock) (free ?d - dock))
  (:functions (battery ?r - robot) (total-cost) - number)
  (:action dock
    :parameters (?r - robot ?d - dock)
    :precondition (and (free ?d) (< (battery ?r) 50))
    :effect (and (docked ?r ?d) (not (free ?d)) (increase (total-cost) 1))))
"""

UNTYPED = """\
(define (domain switches)
  (:requirements :strips)
  (:predicates (on ?s) (off ?s))
  (:action flip :parameters (?s) :precondition (off ?s) :effect (and (on ?s) (not (off ?s)))))
"""


def parcels(**kwargs: str) -> KnowledgeBase:
    kb = KnowledgeBase.from_text(PARCELS, domain_name="parcels.pddl", **kwargs)
    kb.add_instance("t1", "truck")
    for place in ("north", "south"):
        kb.add_instance(place, "place")
    kb.add_instance("box", "parcel")
    kb.add_facts(
        [
            "(at t1 depot)",
            "(parcel-at box north)",
            *(
                f"(road {a} {b})"
                for a in ("depot", "north", "south")
                for b in ("depot", "north", "south")
                if a != b
            ),
        ]
    )
    return kb


def refused(kb: KnowledgeBase, change: object, *fragments: str) -> str:
    """``change()`` is refused with every fragment in the message; nothing changed."""
    before = (kb.version, kb.problem_pddl())
    with pytest.raises(KnowledgeError) as info:
        change()  # type: ignore[operator]
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)
    assert (kb.version, kb.problem_pddl()) == before
    return str(info.value)


def test_a_problem_built_change_by_change_is_pddl_that_loads_and_plans() -> None:
    kb = parcels(name="deliver-box")
    kb.set_goal("(and (parcel-at box south))")
    text = kb.problem_pddl()
    assert text.startswith("(define (problem deliver-box)\n  (:domain parcels)\n")
    assert "    t1 - truck\n    north south - place\n    box - parcel\n" in text
    assert "depot - place" not in text  # a constant of the domain, not an object of the problem
    assert "  (:goal (and\n    (parcel-at box south)\n  ))\n)\n" in text
    task = load_task_from_text(PARCELS, text)
    assert task.goal_facts == (("parcel-at", "box", "south"),)
    assert task.initial_facts == kb.facts
    built = kb.task()
    assert kb.task() is built  # kept until something changes
    assert kb.describes(built)
    result = get_planner("fast-downward").solve(built, timeout=30)
    assert result.solved, result.explanation
    assert [str(s) for s in result.actions][-1] == "(unload box t1 south)"


def test_every_refusal_names_what_is_wrong_and_what_is_allowed() -> None:
    kb = parcels()
    refused(
        kb,
        lambda: kb.add_fact("(parcel_at box north)"),
        "unknown predicate 'parcel_at'",
        "did you mean 'parcel-at'?",
        "predicates of domain parcels: at, road, parcel-at, loaded",
    )
    refused(
        kb,
        lambda: kb.add_fact("(at t1)"),
        "at takes 2 argument(s), got 1",
        "signature: (at ?v - vehicle ?p - place)",
    )
    refused(
        kb,
        lambda: kb.add_fact("(at t1 nort)"),
        "unknown object 'nort'",
        "did you mean 'north'?",
        "objects of type place: depot, north, south",
        "add it first as an instance: nort - place",
    )
    refused(
        kb,
        lambda: kb.add_fact("(at box north)"),
        "'box' is a parcel, but ?v of at takes a vehicle",
        "objects of type vehicle: t1",
    )
    refused(
        kb,
        lambda: kb.add_instance("t2", "truk"),
        "unknown type 'truk'",
        "did you mean 'truck'?",
        "types of domain parcels: object, vehicle, place, parcel, truck",
    )
    refused(kb, lambda: kb.add_instance("t1", "vehicle"), "'t1' is a truck already")
    refused(
        kb, lambda: kb.add_instance("depot", "place"), "'depot' is a constant of domain parcels"
    )
    refused(
        kb, lambda: kb.add_instance("drive", "place"), "the name of an action", "distinct names"
    )
    refused(kb, lambda: kb.add_instance("road", "place"), "the name of a predicate")
    refused(kb, lambda: kb.add_instance("2nd", "place"), "a PDDL name starts with a letter")
    refused(kb, lambda: kb.add_instance("and", "place"), "not a keyword")
    refused(
        kb,
        lambda: kb.set_goal("(or (at t1 north) (at t1 south))"),
        "(or ...) is not supported",
        "conjunctions of ground atoms",
    )
    refused(kb, lambda: kb.set_goal("(and (not (at t1 north)))"), "(not ...) is not supported")
    refused(kb, lambda: kb.set_goal("(at ?v north)"), "?v is a variable")
    refused(kb, lambda: kb.set_goal("(and (at t1 north)"), "unbalanced '('")
    refused(kb, lambda: kb.set_goal("at t1 north"), "expected an atom in parentheses")
    refused(
        kb,
        lambda: kb.remove_instance("truck9"),
        "no instance 'truck9'",
        "instances: t1, north, south, box",
    )
    refused(kb, lambda: kb.remove_instance("depot"), "a constant of domain parcels")
    # A refusal is a FactError, so a ValueError (the operator API and ROS answer it as one).
    assert issubclass(KnowledgeError, FactError) and issubclass(KnowledgeError, ValueError)


def test_numbers_and_action_costs_go_into_the_problem() -> None:
    kb = KnowledgeBase.from_text(CHARGING, name="recharge")
    kb.add_instance("r2", "robot")
    kb.add_instance("d1", "dock")
    kb.add_fact("(free d1)")
    assert kb.set_value("(battery r2)", 12.5)
    assert not kb.set_value(("battery", "r2"), 12.5)  # unchanged: no new version
    refused(kb, lambda: kb.set_value("(battery r2)", float("nan")), "not a finite number")
    refused(
        kb,
        lambda: kb.set_value("(free d1)", 3),
        "'free' is a predicate, not a function; add it as a fact",
    )
    refused(
        kb,
        lambda: kb.add_fact("(battery r2)"),
        "'battery' is a function, not a predicate",
        "(= (battery r2) 10)",
    )
    kb.set_goal([("docked", "r2", "d1")])
    text = kb.problem_pddl()
    assert "    (= (battery r2) 12.5)\n    (= (total-cost) 0)\n" in text
    assert "  (:metric minimize (total-cost))\n)\n" in text
    task = kb.task()
    assert initial_values(task) == {("battery", "r2"): 12.5}
    assert kb.remove_value("(battery r2)")
    assert "battery" not in kb.problem_pddl()
    assert not kb.remove_value("(battery r2)")


def test_removing_a_used_instance_is_refused_unless_it_cascades() -> None:
    kb = parcels()
    kb.add_goal("(parcel-at box south)")
    message = refused(kb, lambda: kb.remove_instance("box"), "instance 'box' is used by")
    assert "1 fact(s) ((parcel-at box north))" in message
    assert "1 goal atom(s) ((parcel-at box south))" in message
    assert "or remove the instance with cascade" in message
    assert kb.remove_instance("box", cascade=True)
    assert "box" not in kb.instances
    assert not any("box" in fact for fact in kb.facts)
    assert kb.goal == ()
    kb.add_instance("spare", "parcel")
    assert kb.remove_instance("spare")  # used by nothing: no cascade needed


def test_listeners_get_every_change_with_its_version_kind_and_source() -> None:
    kb = KnowledgeBase.from_text(PARCELS)
    seen: list[KnowledgeChange] = []
    kb.add_listener(seen.append)
    kb.add_instance("t1", "truck", source="ros")
    assert not kb.add_instance("T1", "TRUCK")  # PDDL is case-insensitive: already there
    kb.add_fact("(at t1 depot)")
    assert not kb.add_fact("(AT t1 depot)")
    kb.set_goal("(at t1 depot)")
    assert not kb.set_goal("(and (at t1 depot))")
    kb.remove_fact("(at t1 depot)", source="commands:4")
    assert [(c.version, c.kind, c.source) for c in seen] == [
        (1, "instance", "ros"),
        (2, "fact", "api"),
        (3, "goal", "api"),
        (4, "fact", "commands:4"),
    ]
    assert str(seen[0]) == "instance t1 - truck added (ros)"
    assert [c.changes_objects_or_goal for c in seen] == [True, False, True, False]
    assert kb.version == 4
    kb.remove_listener(seen.append)
    kb.clear()
    assert len(seen) == 4 and kb.version == 5
    assert kb.to_json() == {
        "problem": "problem",
        "domain": "parcels",
        "version": 5,
        "instances": {},
        "facts": [],
        "values": [],
        "goal": [],
    }


def test_goal_atoms_can_be_set_added_and_removed() -> None:
    kb = parcels()
    assert kb.set_goal("(and (at t1 north) (parcel-at box south))")
    assert kb.add_goal("(at t1 north) (loaded box t1)") == [("loaded", "box", "t1")]
    assert kb.remove_goal([("at", "t1", "north")]) == [("at", "t1", "north")]
    assert kb.goal == (("parcel-at", "box", "south"), ("loaded", "box", "t1"))
    assert kb.clear_goal() and kb.goal == ()
    assert "  (:goal (and\n  ))\n" in kb.problem_pddl()  # the empty goal: valid PDDL
    load_task_from_text(PARCELS, kb.problem_pddl())


def test_a_task_becomes_a_knowledge_base_and_back() -> None:
    kb = parcels()
    kb.set_goal("(parcel-at box south)")
    task = load_task_from_text(PARCELS, kb.problem_pddl())
    again = KnowledgeBase.from_task(task)
    assert again.instances == kb.instances
    assert again.facts == kb.facts
    assert again.goal == kb.goal
    assert again.constants == {"depot": "place"}
    assert again.describes(task)
    assert again.problem_pddl() == kb.problem_pddl()
    numeric = load_task_from_text(
        CHARGING,
        "(define (problem p) (:domain charging) (:objects r - robot d - dock)"
        " (:init (free d) (= (battery r) 7) (= (total-cost) 0)) (:goal (docked r d))"
        " (:metric minimize (total-cost)))",
    )
    assert KnowledgeBase.from_task(numeric).values == {("battery", "r"): 7.0}


def test_a_domain_file_an_untyped_domain_and_a_bad_domain(tmp_path: Path) -> None:
    path = tmp_path / "switches.pddl"
    path.write_text(UNTYPED)
    kb = KnowledgeBase(path, name="lights")
    kb.add_instance("s1")
    kb.add_instance("s2", "object")
    kb.add_fact("(off s1)")
    kb.set_goal("(on s1)")
    text = kb.problem_pddl()
    assert "  (:objects\n    s1 s2\n  )\n" in text
    task = kb.task()
    assert task.objects == {"s1": "object", "s2": "object"}
    refused(
        kb,
        lambda: kb.add_instance("s3", "switch"),
        "unknown type 'switch'",
        "types of domain switches: object",
    )
    bad = tmp_path / "bad.pddl"
    bad.write_text(PARCELS.replace("(road ?a ?b - place)", "(road ?a ?b - plaice)"))
    with pytest.raises(PddlError, match=r"bad\.pddl:"):
        KnowledgeBase(bad)


def test_changes_from_many_threads_are_all_kept() -> None:
    kb = KnowledgeBase.from_text(UNTYPED)
    names = [f"s{i}" for i in range(200)]

    def work(part: list[str]) -> None:
        for name in part:
            kb.add_instance(name)
            kb.add_fact(f"(off {name})")
            kb.add_goal(f"(on {name})")

    threads = [threading.Thread(target=work, args=(names[i::8],)) for i in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    assert len(kb.instances) == len(kb.facts) == len(kb.goal) == 200
    assert kb.version == 600
    assert len(load_task_from_text(UNTYPED, kb.problem_pddl()).objects) == 200


def test_the_text_forms_of_goals_values_and_atoms() -> None:
    assert goal_atoms("(and(robot_at leia bathroom))") == [("robot_at", "leia", "bathroom")]
    assert goal_atoms("(AND (a x) (and (b y)))") == [("a", "x"), ("b", "y")]
    assert goal_atoms("(and)") == []
    assert value_assignments("(= (battery leia) 100) (= (load t1) -2.5)") == [
        (("battery", "leia"), 100.0),
        (("load", "t1"), -2.5),
    ]
    assert function_atom("battery leia") == function_atom("(battery leia)") == ("battery", "leia")
    assert function_atom("(= (battery leia) 3)") == ("battery", "leia")
    for read, bad, fragment in (
        (value_assignments, "(= (battery leia) lots)", "'lots' is not a number"),
        (value_assignments, "(battery leia 100)", "expected (= (function args...) number)"),
        (function_atom, "(battery leia) (load t1)", "expected one atom"),
        (function_atom, "(a))", "unbalanced ')'"),
        (goal_atoms, "(" * 40 + ")" * 40, "nested deeper than 32"),
        (goal_atoms, "(a " + "x " * 60_000 + ")", "longer than 100000 characters"),
    ):
        with pytest.raises(KnowledgeError, match=re.escape(fragment)):
            read(bad)  # type: ignore[operator]
