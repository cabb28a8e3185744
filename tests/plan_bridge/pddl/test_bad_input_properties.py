"""Property-based bad input: whatever the text, loading ends in a task or a PddlError."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.task import load_task_from_text

DATA = Path(__file__).parents[1] / "data" / "rooms"
DOMAIN = (DATA / "domain.pddl").read_text()
PROBLEM = (DATA / "problems" / "p01.pddl").read_text()

TOKENS = st.sampled_from(
    [
        "(",
        ")",
        "define",
        "domain",
        ":action",
        ":parameters",
        "?x",
        "-",
        "robot",
        ":effect",
        "and",
        "not",
        ":requirements",
        ":strips",
        ":typing",
        ":precondition",
        "(at ?r ?x)",
        "\n",
        " ",
        "either",
        ":types",
        "forall",
        "when",
        "=",
        "1.5",
        ";comment\n",
        "\x00",
        "é",
    ]
)


def _load(domain: str, problem: str) -> None:
    """Either a task, or a PlanBridgeError with a message (anything else fails the test)."""
    try:
        task = load_task_from_text(domain, problem)
    except PlanBridgeError as exc:
        assert str(exc).strip()
        assert "Traceback" not in str(exc)
    else:
        assert task.actions


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cut=st.integers(min_value=0, max_value=len(DOMAIN)))
def test_truncated_domains_are_rejected_with_pddl_errors(cut: int) -> None:
    _load(DOMAIN[:cut], PROBLEM)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tokens=st.lists(TOKENS, max_size=60))
def test_token_soup_problems_never_escape_as_other_exceptions(tokens: list[str]) -> None:
    _load(DOMAIN, " ".join(tokens))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.text(max_size=300))
def test_arbitrary_text_as_a_domain_is_rejected_cleanly(data: str) -> None:
    _load(data, PROBLEM)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    position=st.integers(min_value=0, max_value=len(PROBLEM) - 1),
    char=st.sampled_from("()?-:\x00 "),
)
def test_one_character_mutations_load_or_fail_cleanly(position: int, char: str) -> None:
    _load(DOMAIN, PROBLEM[:position] + char + PROBLEM[position + 1 :])


def test_deep_nesting_is_refused_before_the_parser_sees_it() -> None:
    deep = "(define (domain d) " + "(and " * 5000 + ")" * 5001
    with pytest.raises(PlanBridgeError, match="nest"):
        load_task_from_text(deep, PROBLEM)


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run"], "give a TARGET"),
        (["run", str(DATA), "--seed", "-1"], "expected a whole number >= 0"),
        (["run", str(DATA), "--fail-rate", "2"], "between 0 and 1"),
        (["run", str(DATA), "--policy", "magic"], "unknown replanning policy 'magic'"),
        (["run", str(DATA), "--problem", "p99"], "no such problem; problems of rooms: p01, p02"),
        (["run", str(DATA), "--planner", "no-such-engine"], "no-such-engine"),
        (["check", str(DATA / "domain.pddl")], "needs a problem file"),
        (["study", str(DATA), "--approaches", "telepathy"], "unknown approaches ['telepathy']"),
        (["plan", "/dev/null", "/dev/null"], "/dev/null"),
        (["frobnicate"], "invalid choice: 'frobnicate'"),
    ],
)
def test_bad_cli_arguments_exit_2_with_a_message_and_no_traceback(
    args: list[str], message: str
) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "plan_bridge", *args], capture_output=True, text=True, timeout=100
    )
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert message in result.stderr
