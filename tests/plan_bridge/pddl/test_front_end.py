"""The positioned front end: rewriting for UP with positions kept, feature
classification, engines that are not installed, UP's failures mapped back."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.errors import PddlError, UnsupportedFeatureError
from plan_bridge.pddl import features
from plan_bridge.pddl.front_end import analyse
from plan_bridge.pddl.sexpr import read_tree
from plan_bridge.pddl.source import UP_REQUIREMENTS, SourceText, check_source, decode_source
from plan_bridge.pddl.task import load_task_from_text

CORPUS = Path(__file__).parent / "corpus"
DOMAIN = (CORPUS / "base" / "domain.pddl").read_text()
PROBLEM = (CORPUS / "base" / "problem.pddl").read_text()

TEMPORAL = """(define (domain t)
  (:requirements :typing :durative-actions :numeric-fluents :duration-inequalities)
  (:durative-action go
    :parameters (?r - robot)
    :duration (>= ?duration 1)
    :condition (at start (ready ?r))
    :effect (at end (increase (odo ?r) ?duration)))
  (:types robot)
  (:functions (odo ?r - robot))
  (:predicates (ready ?r - robot)))
"""
TEMPORAL_PROBLEM = (
    "(define (problem p) (:domain t) (:objects r - robot) (:init (ready r) (= (odo r) 0)) "
    "(:goal (> (odo r) 0)))"
)


def _source(text: str, kind: str, name: str = "") -> SourceText:
    source = decode_source(text.encode(), name or f"{kind}.pddl", kind)
    check_source(source)
    return source


def test_reordered_sections_keep_every_offset_of_the_original() -> None:
    domain = DOMAIN.replace("  (:types robot place parcel - object)\n", "").replace(
        "  (:action unload", "  (:types robot place parcel - object)\n  (:action unload"
    )
    front = analyse(_source(domain, "domain"), _source(PROBLEM, "problem"))
    rewritten = front.domain_up
    assert rewritten.changed
    assert rewritten.text.index("(:types") < rewritten.text.index("(:predicates")
    for word in ("(:types", "(:action unload", "(lies ?c ?p)", "(:predicates"):
        assert rewritten.original_offset(rewritten.text.index(word)) == domain.index(word)


def test_unchanged_text_is_handed_to_unified_planning_as_it_is() -> None:
    front = analyse(_source(DOMAIN, "domain"), _source(PROBLEM, "problem"))
    assert front.domain_text == DOMAIN
    assert front.problem_text == PROBLEM
    assert not front.domain_up.changed


def test_a_failure_of_unified_planning_is_shown_at_the_line_of_the_original_file() -> None:
    # UP 1.3 cannot read a duration with only a lower bound; the action comes first in
    # the user's file but after the types in the text UP reads.
    with pytest.raises(PddlError) as caught:
        load_task_from_text(TEMPORAL, TEMPORAL_PROBLEM, domain_name="t.pddl")
    error = caught.value
    assert error.path == "t.pddl"
    assert error.line == 5
    assert "(>= ?duration 1)" in error.excerpt
    assert "unified-planning rejected this PDDL" in error.explanation


def test_a_feature_whose_engines_are_not_installed_is_refused_at_its_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(features, "is_installed", lambda engine: engine == "fast-downward")
    front = analyse(_source(TEMPORAL, "domain", "t.pddl"), _source(TEMPORAL_PROBLEM, "problem"))
    with pytest.raises(UnsupportedFeatureError) as caught:
        front.require_engines()
    error = caught.value
    assert error.path == "t.pddl"
    assert error.line == 3  # the first durative action
    assert "up-kairos" in error.explanation and "not installed" in error.explanation
    assert "pip install up-kairos" in error.hint
    assert any("not installed" in warning for warning in front.warnings)


def test_a_feature_with_an_installed_engine_is_accepted(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(features, "is_installed", lambda engine: True)
    front = analyse(_source(TEMPORAL, "domain"), _source(TEMPORAL_PROBLEM, "problem"))
    front.require_engines()
    assert front.needs_engine == []


def test_every_requirement_unified_planning_reads_is_classified() -> None:
    for flag in UP_REQUIREMENTS:
        support = features.classify(flag)
        assert support is not None, flag
        assert support.status in ("supported", "engine", "unsupported")
        assert support.describe().startswith(flag)


def test_contingent_and_probabilistic_constructs_are_named_not_called_typos() -> None:
    for construct in (":observe", "oneof", "unknown", "probabilistic"):
        support = features.classify(construct)
        assert support is not None and support.status == "unsupported"
        assert "typo" not in support.describe()
    assert "contingent" in features.classify(":observe").describe()  # type: ignore[union-attr]
    assert "probabilistic" in features.classify("probabilistic").describe()  # type: ignore[union-attr]


def test_a_requirement_refusal_lists_unsupported_flags_apart_from_supported_ones() -> None:
    text = DOMAIN.replace(":negative-preconditions)", ":negative-preconditions :contingnet)")
    with pytest.raises(PddlError) as caught:
        _source(text, "domain")
    supported, _, rest = caught.value.hint.partition("; through")
    assert ":contingent" not in supported and ":strips" in supported
    assert ":durative-actions" in rest.split("known but not supported")[0]
    assert ":contingent" in rest.split("known but not supported")[1]
    assert "did you mean :contingent?" in caught.value.explanation


def test_engines_of_the_classification_name_their_packages() -> None:
    for support in features.known():
        for engine in support.engines:
            assert features.ENGINES[engine].package.startswith("up-")


def test_mixed_case_names_are_read_in_lower_case() -> None:
    task = load_task_from_text(DOMAIN.upper(), PROBLEM.upper())
    assert "drive" in task.actions
    assert ("at", "van", "depot") in task.initial_facts


def test_several_errors_are_reported_together_first_one_in_front() -> None:
    domain = DOMAIN.replace("(link ?from ?to))", "(road ?from ?to))").replace(
        "(empty ?r) (not (carries", "(emtpy ?r) (not (carries"
    )
    with pytest.raises(PddlError) as caught:
        load_task_from_text(domain, PROBLEM)
    error = caught.value
    assert "undeclared predicate 'road'" in error.explanation
    assert "1 more problem(s)" in error.hint and "'emtpy'" in error.hint


def test_tree_positions_point_at_the_words() -> None:
    source = _source(DOMAIN, "domain")
    tree = read_tree(source)
    header = tree.items[1]
    assert not isinstance(header, str)
    name = header.items[1]  # type: ignore[union-attr]
    assert source.line_col(name.offset) == (1, 17)


def test_front_end_warnings_reach_the_task() -> None:
    domain = DOMAIN.replace("  (:requirements :strips :typing :negative-preconditions)\n", "")
    task = load_task_from_text(domain, PROBLEM, domain_name="d.pddl")
    assert any(w.startswith("d.pddl:2:") and ":typing" in w for w in task.warnings)
