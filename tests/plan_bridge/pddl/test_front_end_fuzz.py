"""Fuzzing the front end: whatever the text, a verdict with a position, never a
traceback or a hang; huge input is bounded."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plan_bridge.errors import PddlError
from plan_bridge.pddl.front_end import analyse
from plan_bridge.pddl.source import SourceText, check_source, decode_source
from plan_bridge.pddl.task import load_task_from_text

CORPUS = Path(__file__).parent / "corpus"
DOMAIN = (CORPUS / "base" / "domain.pddl").read_text()
PROBLEM = (CORPUS / "base" / "problem.pddl").read_text()

WORDS = st.sampled_from(
    [
        "(",
        ")",
        "(and",
        "(not",
        "?r",
        "?x",
        "-",
        "robot",
        "place",
        ":effect",
        ":parameters",
        "(:types",
        "(:action",
        "(at",
        "oneof",
        "(=",
        "1",
        "(increase",
        "(either",
        " ",
        "\n",
        ";c\n",
        "(:functions)",
        "(:constants)",
        "van",
        "forall",
        "(exists",
        "Robot",
        "\t",
    ]
)


@st.composite
def mutated(draw: st.DrawFn, text: str) -> str:
    """``text`` with a few slices deleted, duplicated or replaced by PDDL-ish words."""
    for _ in range(draw(st.integers(1, 3))):
        start = draw(st.integers(0, len(text)))
        end = draw(st.integers(start, min(len(text), start + 40)))
        action = draw(st.sampled_from(["delete", "duplicate", "insert"]))
        if action == "delete":
            text = text[:start] + text[end:]
        elif action == "duplicate":
            text = text[:end] + text[start:end] + text[end:]
        else:
            text = text[:start] + " ".join(draw(st.lists(WORDS, max_size=6))) + text[start:]
    return text


def _front_end(domain: str, problem: str) -> None:
    sources: list[SourceText] = []
    for text, kind in ((domain, "domain"), (problem, "problem")):
        source = decode_source(text.encode(), f"{kind}.pddl", kind)
        check_source(source)
        sources.append(source)
    analyse(*sources)


def _assert_positioned(error: PddlError) -> None:
    assert error.path in ("domain.pddl", "problem.pddl", "<domain>", "<problem>"), str(error)
    if "is empty" not in error.explanation:
        assert error.line is not None, str(error)
    assert "Traceback" not in str(error)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(domain=mutated(DOMAIN), problem=mutated(PROBLEM))
def test_any_mutation_gets_a_verdict_and_every_error_a_line(domain: str, problem: str) -> None:
    try:
        _front_end(domain, problem)
    except PddlError as error:
        _assert_positioned(error)


@pytest.mark.timeout(300)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(domain=mutated(DOMAIN))
def test_what_the_front_end_accepts_unified_planning_reads_or_is_located(domain: str) -> None:
    try:
        load_task_from_text(domain, PROBLEM, domain_name="domain.pddl", problem_name="problem.pddl")
    except PddlError as error:
        _assert_positioned(error)


@pytest.mark.timeout(120)
def test_a_10_mb_text_is_refused_by_the_size_limit_without_parsing() -> None:
    facts = "".join("    (link depot shop)\n" for _ in range(10_000_000 // 22))
    problem = PROBLEM.replace("(link shop depot))", "(link shop depot)\n" + facts + ")")
    assert len(problem) > 10_000_000
    with pytest.raises(PddlError) as caught:
        load_task_from_text(DOMAIN, problem)
    assert "larger than the 5.0 MB limit" in caught.value.explanation


@pytest.mark.timeout(300)
def test_a_10_mb_problem_is_analysed_when_the_limit_allows_it() -> None:
    objects = "".join(f" p{i}" for i in range(200_000))
    facts = "".join(f"(link p{i} p{i + 1})" for i in range(199_999)) * 3
    problem = PROBLEM.replace("depot shop - place", "depot shop" + objects + " - place").replace(
        "(link shop depot))", "(link shop depot)" + facts + ")"
    )
    assert len(problem) > 10_000_000
    domain_source = decode_source(DOMAIN.encode(), "domain.pddl", "domain")
    problem_source = decode_source(problem.encode(), "problem.pddl", "problem")
    check_source(problem_source, max_bytes=20_000_000)
    front = analyse(domain_source, problem_source)
    assert len(front.problem_model.objects) == 200_004


@pytest.mark.timeout(60)
def test_nesting_a_hundred_thousand_deep_is_refused_with_a_line() -> None:
    domain = DOMAIN.replace("(link ?from ?to))", "(and " * 100_000 + ")" * 100_000 + ")")
    with pytest.raises(PddlError) as caught:
        load_task_from_text(domain, PROBLEM)
    assert "nested deeper than 200" in caught.value.explanation
    assert caught.value.line is not None
