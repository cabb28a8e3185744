"""A fleet's goal shared out: atoms grouped into jobs, jobs given by route cost."""

from __future__ import annotations

from typing import Any

from plan_bridge.fleet.jobs import Job, allocate, jobs_of
from plan_bridge.maps.tasks import RouteTasks


def test_atoms_about_one_object_or_robot_are_one_job(house: Any) -> None:
    view = RouteTasks(house(rover=True))
    goal = [
        ("at", "apple", "shelf_top"),
        ("at", "pear", "desk_top"),
        ("at", "rover", "kitchen"),
        ("holding", "rover", "pear"),
    ]
    jobs = jobs_of(goal, ["robot", "rover"], view.belief(), view)
    assert sorted(str(job) for job in jobs) == [
        "(at apple shelf_top)",
        "(at pear desk_top) (at rover kitchen) (holding rover pear)",
    ]
    (pear,) = [job for job in jobs if job.robot is not None]
    assert pear.robot == "rover"
    (apple,) = [job for job in jobs if job.robot is None]
    assert (apple.start, apple.end) == ("desk_top", "shelf_top")


def test_what_a_robot_holds_is_its_own_job(house: Any) -> None:
    view = RouteTasks(house(holding="apple", rover=True))
    (job,) = jobs_of([("at", "apple", "shelf_top")], ["robot", "rover"], view.belief(), view)
    assert job.robot == "robot"


def test_each_job_goes_to_the_robot_that_finishes_it_first(house: Any) -> None:
    view = RouteTasks(house(rover=True))
    belief = view.belief()
    jobs = [
        Job((("at", "apple", "desk_top"),), None, "desk_top", "desk_top"),
        Job((("at", "pear", "shelf_top"),), None, "shelf_top", "shelf_top"),
    ]
    shares = allocate(jobs, ["robot", "rover"], belief, view, frozenset())
    # The kitchen robot is next to the desk, the rover in the bedroom next to the shelf.
    assert {robot: [str(j) for j in js] for robot, js in shares.items()} == {
        "robot": ["(at apple desk_top)"],
        "rover": ["(at pear shelf_top)"],
    }
    # With the hallway closed, the rover cannot get to the desk: the robot gets both.
    both = [jobs[0], Job((("at", "apple", "desk_top"),), None, "desk_top", "desk_top")]
    alone = allocate(both, ["robot", "rover"], belief, view, frozenset({"corridor"}))
    assert list(alone) == ["robot"]
