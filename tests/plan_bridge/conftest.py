"""Fixtures for plan_bridge tests: the shared IPC benchmark set and small domains."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
BENCH_ROOT = (REPO_ROOT / ".." / "shared" / "pddl-bench").resolve()

#: Domains unified-planning 1.3 cannot parse (see test_domain).
UNPARSEABLE = {"storage"}

SLOW_TO_SOLVE = {
    "visitall-sat11-strips/problem12",
    "visitall-sat11-strips/problem14",
    "miconic/s10-0",
}


def bench_problems(*, parseable: bool = True) -> list[tuple[Path, Path]]:
    """(domain, problem) pairs of the shared benchmark set."""
    pairs = []
    if not BENCH_ROOT.is_dir():
        return pairs
    for domain_dir in sorted(p for p in BENCH_ROOT.iterdir() if p.is_dir()):
        if (domain_dir.name in UNPARSEABLE) == parseable:
            continue
        for problem in sorted(domain_dir.glob("*.pddl")):
            if problem.name != "domain.pddl":
                pairs.append((domain_dir / "domain.pddl", problem))
    return pairs


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "bench_problem" in metafunc.fixturenames:
        # Solving and validating these takes more than 2 s each (UP's plan validator
        # is slow on 200+ step plans); loading them is quick.
        slow = SLOW_TO_SOLVE if "solves" in metafunc.function.__name__ else set()
        metafunc.parametrize(
            "bench_problem",
            [
                pytest.param(
                    (d, p),
                    id=f"{d.parent.name}/{p.stem}",
                    marks=[pytest.mark.slow] if f"{d.parent.name}/{p.stem}" in slow else [],
                )
                for d, p in bench_problems()
            ],
        )


@pytest.fixture(scope="session")
def bench() -> Path:
    """The shared benchmark folder (../shared/pddl-bench next to the repository)."""
    if not BENCH_ROOT.is_dir():
        pytest.skip(f"benchmark set not found at {BENCH_ROOT}")
    return BENCH_ROOT


DOORS_DOMAIN = """\
; A robot moves between rooms; a locked room opens only with its key.
(define (domain doors)
  (:requirements :strips :typing)
  (:types room key)
  (:predicates (at ?r - room) (open ?r - room) (has ?k - key)
               (connected ?a ?b - room) (key-for ?k - key ?r - room))
  (:action move
    :parameters (?a ?b - room)
    :precondition (and (at ?a) (connected ?a ?b) (open ?b))
    :effect (and (at ?b) (not (at ?a))))
  (:action unlock
    :parameters (?k - key ?r - room)
    :precondition (and (has ?k) (key-for ?k ?r))
    :effect (open ?r)))
"""

DOORS_PROBLEM = """\
(define (problem fetch) (:domain doors)
  (:objects hall kitchen vault - room k1 - key)
  (:init (at hall) (open kitchen) (connected hall kitchen) (connected kitchen vault)
         (key-for k1 vault) {extra})
  (:goal (and {goal})))
"""


@pytest.fixture
def doors(tmp_path: Path):  # type: ignore[no-untyped-def]
    """A factory writing the doors domain and a problem: doors(goal, extra_init)."""

    def write(goal: str = "(at vault)", extra: str = "(has k1)") -> tuple[Path, Path]:
        domain = tmp_path / "domain.pddl"
        problem = tmp_path / "problem.pddl"
        domain.write_text(DOORS_DOMAIN)
        problem.write_text(DOORS_PROBLEM.format(goal=goal, extra=extra))
        return domain, problem

    return write


@pytest.fixture
def doors_text() -> tuple[str, str]:
    """(domain text, problem template with {goal} and {extra} placeholders)."""
    return DOORS_DOMAIN, DOORS_PROBLEM


def map_house(
    *,
    hall_open: bool = True,
    desk_locked: bool = False,
    holding: str | None = None,
    rover: bool = False,
) -> Any:
    """A world model built by hand (no pyrobosim): two rooms joined by a hallway, a desk
    (one spawn) in the kitchen, a shelf in the bedroom; a robot in the kitchen (and,
    with ``rover``, a second robot in the bedroom), an apple on the desk, a pear on
    the shelf."""
    from plan_bridge.maps.model import Gate, Hall, Place, RobotInfo, WorldModel

    places = {
        "kitchen": Place("kitchen", 0.0, 0.0, "kitchen", aliases=("kitchen",)),
        "bedroom": Place("bedroom", 10.0, 0.0, "bedroom", aliases=("bedroom",)),
        "corridor_door_kitchen": Place(
            "corridor_door_kitchen",
            4.0,
            0.0,
            "kitchen",
            doors=("corridor",),
            aliases=("corridor_door_kitchen",),
        ),
        "corridor_door_bedroom": Place(
            "corridor_door_bedroom",
            6.0,
            0.0,
            "bedroom",
            doors=("corridor",),
            aliases=("corridor_door_bedroom",),
        ),
        "desk_top": Place(
            "desk_top", 1.0, 1.0, "kitchen", ("desk_top",), "desk", aliases=("desk_top",)
        ),
        "shelf_top": Place(
            "shelf_top", 9.0, 1.0, "bedroom", ("shelf_top",), "shelf", aliases=("shelf_top",)
        ),
    }
    gates = {
        "corridor": Gate("corridor", "hall", hall_open, not hall_open),
        "desk": Gate("desk", "fixture", not desk_locked, desk_locked, spawns=("desk_top",)),
        "shelf": Gate("shelf", "fixture", True, False, spawns=("shelf_top",)),
    }
    halls = {
        "corridor": Hall(
            "corridor",
            ("corridor_door_kitchen", "corridor_door_bedroom"),
            ("kitchen", "bedroom"),
            2.0,
            ((4.0, 0.0), (6.0, 0.0)),
        )
    }
    kinds = {"kitchen": "room", "bedroom": "room", "desk_top": "spawn", "shelf_top": "spawn"}
    kinds |= {"corridor_door_kitchen": "door", "corridor_door_bedroom": "door"}
    robots = (RobotInfo("robot", "kitchen", 90.0, 1.0, 0.5, holding),)
    if rover:
        robots = (*robots, RobotInfo("rover", "bedroom", 90.0, 1.0, 0.5))
    return WorldModel(
        "house",
        robots,
        places,
        gates,
        halls,
        {"apple": None if holding == "apple" else "desk_top", "pear": "shelf_top"},
        {"apple": "apple", "pear": "pear"},
        {name: name for name in places},
        kinds,
    )


@pytest.fixture
def house() -> Any:
    """:func:`map_house`: call it with its options."""
    return map_house


@pytest.fixture
def kairos() -> Any:
    """Kairos in a pool of two planner processes of the test's own (closed after)."""
    from plan_bridge.planning.planner import UPPlanner
    from plan_bridge.planning.worker import WorkerPool

    pool = WorkerPool(max_workers=2)
    yield UPPlanner("kairos", pool=pool)
    pool.close()
