"""Writing PDDL problems and the command line of problem generators."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem
from plan_bridge.pddl.task import load_task_from_text

ROOMS_DOMAIN = (Path(__file__).parents[1] / "data" / "rooms" / "domain.pddl").read_text()


def _problem(*, compact: bool) -> str:
    return pddl_problem(
        "carry-cup",
        "rooms",
        objects=["robot1 - robot", "hall kitchen - room", "cup - item"],
        init=[
            "(at robot1 hall)",
            "(free robot1)",
            "(item-at cup kitchen)",
            *both_ways("hall", "kitchen", "connected", "open"),
        ],
        goal=["(item-at cup hall)", "(free robot1)"],
        comment="a cup in the kitchen",
        compact=compact,
    )


def test_both_ways_writes_each_relation_in_both_directions() -> None:
    assert both_ways("a", "b", "connected", "clear") == [
        "(connected a b)",
        "(connected b a)",
        "(clear a b)",
        "(clear b a)",
    ]
    assert both_ways("a", "b", "door-between d1") == [
        "(door-between d1 a b)",
        "(door-between d1 b a)",
    ]


def test_problem_text_has_one_object_line_and_one_fact_per_line() -> None:
    assert _problem(compact=False) == (
        "; a cup in the kitchen\n"
        "(define (problem carry-cup)\n"
        "  (:domain rooms)\n"
        "  (:objects\n"
        "    robot1 - robot\n"
        "    hall kitchen - room\n"
        "    cup - item)\n"
        "  (:init\n"
        "    (at robot1 hall)\n"
        "    (free robot1)\n"
        "    (item-at cup kitchen)\n"
        "    (connected hall kitchen)\n"
        "    (connected kitchen hall)\n"
        "    (open hall kitchen)\n"
        "    (open kitchen hall)\n"
        "  )\n"
        "  (:goal (and\n"
        "    (item-at cup hall)\n"
        "    (free robot1)\n"
        "  )))\n"
    )


def test_compact_problem_text_starts_sections_on_their_keywords_line() -> None:
    assert _problem(compact=True) == (
        "; a cup in the kitchen\n"
        "(define (problem carry-cup)\n"
        "  (:domain rooms)\n"
        "  (:objects robot1 - robot\n"
        "            hall kitchen - room\n"
        "            cup - item)\n"
        "  (:init (at robot1 hall)\n"
        "         (free robot1)\n"
        "         (item-at cup kitchen)\n"
        "         (connected hall kitchen)\n"
        "         (connected kitchen hall)\n"
        "         (open hall kitchen)\n"
        "         (open kitchen hall))\n"
        "  (:goal (and (item-at cup hall) (free robot1))))\n"
    )


@pytest.mark.parametrize("compact", [False, True])
def test_both_layouts_load_as_the_same_task(compact: bool) -> None:
    task = load_task_from_text(ROOMS_DOMAIN, _problem(compact=compact))
    assert task.objects_of_type("room") == ("hall", "kitchen")
    assert ("open", "kitchen", "hall") in task.initial_facts
    assert set(task.goal_facts) == {("item-at", "cup", "hall"), ("free", "robot1")}


def test_a_problem_without_comment_or_objects_is_still_well_formed() -> None:
    text = pddl_problem("empty", "rooms", objects=[], init=["(lights-on hall)"], goal=[])
    assert text.startswith("(define (problem empty)\n  (:domain rooms)\n  (:objects)\n")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="generate.py")
    parser.add_argument("--rooms", type=int, default=2)
    return parser


def _make(args: argparse.Namespace) -> str:
    if args.rooms < 1:
        raise ValueError("need --rooms >= 1")
    return f"({args.rooms} rooms)\n"


def test_generator_main_prints_the_problem(capsys: pytest.CaptureFixture[str]) -> None:
    assert generator_main(_parser(), _make, ["--rooms", "3"]) == 0
    assert capsys.readouterr().out == "(3 rooms)\n"


def test_generator_main_reports_arguments_that_make_no_problem_as_a_usage_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit) as exit_:
        generator_main(_parser(), _make, ["--rooms", "0"])
    assert exit_.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "usage: generate.py" in captured.err and "error: need --rooms >= 1" in captured.err
