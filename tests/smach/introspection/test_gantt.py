"""The Gantt rows of temporal plans folded from action_started/action_ended records."""

from __future__ import annotations

from typing import Any

import pytest

from smach.introspection.gantt import MAX_ACTIONS, Timeline, gantt
from smach.introspection.model import History, ViewModel, fold

PLAN = "/ROOT/PLAN"


def _start(t: float, label: str, index: int, start: float, duration: float, **kw: Any) -> dict:
    return {
        "kind": "action_started",
        "path": f"{PLAN}/{label}",
        "time": t,
        "thread": "dispatch",
        "index": index,
        "action": f"(act {index})",
        "planned_start": start,
        "planned_duration": duration,
        "actual_start": kw.get("actual_start", 0.0),
        "time_scale": kw.get("scale", 0.1),
    }


def _end(t: float, label: str, outcome: str = "succeeded") -> dict:
    return {"kind": "action_ended", "path": f"{PLAN}/{label}", "time": t, "outcome": outcome}


def _dispatch(t: float) -> dict:
    return {"kind": "container_started", "path": PLAN, "time": t}


def _scaled_run() -> list[dict]:
    """Two plans at time scale 0.1: a on time, b late, c fails; the replan's d runs."""
    return [
        {"kind": "plan_computed", "path": "/ROOT", "time": 99.0, "status": "solved"},
        _dispatch(100.0),
        _start(100.0, "01_A", 1, 0.0, 5.0),
        _start(100.0, "02_B", 2, 0.0, 2.0),
        _end(100.5, "01_A"),
        _start(100.5, "03_C", 3, 5.0, 3.0, actual_start=0.5),
        _end(100.6, "02_B"),  # planned 2 s = 0.2 wall s: ended at 6 plan seconds
        _end(100.7, "03_C", "aborted"),
        {"kind": "plan_computed", "path": "/ROOT", "time": 100.8, "status": "solved"},
        _dispatch(101.0),
        _start(101.0, "04_D", 4, 7.0, 4.0),
    ]


def test_an_action_started_and_ended_is_one_row_with_planned_and_actual_intervals() -> None:
    model = fold({}, _scaled_run())
    assert model.to_json()["gantt"] == {"rows": 4, "running": 1}  # the page's button
    view = model.gantt_json()
    assert view["axis"] == "plan" and view["time_scale"] == 0.1 and view["dispatches"] == 2
    rows = {row["index"]: row for row in view["rows"]}
    assert [row["index"] for row in view["rows"]] == [1, 2, 3, 4]
    a, b, c, d = rows[1], rows[2], rows[3], rows[4]
    assert (a["p0"], a["p1"], a["a0"], a["a1"]) == pytest.approx((0.0, 5.0, 0.0, 5.0))
    assert (b["p0"], b["p1"], b["a0"], b["a1"]) == pytest.approx((0.0, 2.0, 0.0, 6.0))
    assert (c["p0"], c["p1"], c["a0"], c["a1"]) == pytest.approx((5.0, 8.0, 5.0, 7.0))
    assert [a["outcome"], b["outcome"], c["outcome"]] == ["succeeded", "succeeded", "aborted"]
    assert [row["plan"] for row in view["rows"]] == [1, 1, 1, 2]
    # The replan's dispatch began 1 wall second (10 plan seconds) after the first one,
    # its plan's earliest start (7.0) is placed there.
    assert d["dispatch"] == 1 and (d["p0"], d["p1"], d["a0"]) == pytest.approx((10.0, 14.0, 10.0))


def test_a_running_action_grows_up_to_the_moment_shown() -> None:
    records = _scaled_run()
    history = History({})
    for record in records:
        history.add(record)
    # After C started (6 records): A ended, B and C are running up to C's start time.
    rows = history.view_at(6).gantt_json()["rows"]
    assert [(r["index"], r["running"], r["outcome"]) for r in rows] == [
        (1, False, "succeeded"),
        (2, True, "running"),
        (3, True, "running"),
    ]
    assert rows[1]["a1"] == pytest.approx(5.0) and rows[2]["a1"] == pytest.approx(5.0)
    # Later records move the moment on: a replay at the end has B ended at 6.
    history.add({"kind": "userdata", "path": "/ROOT", "time": 102.0, "values": {}})
    last = history.view_at(history.total).gantt_json()["rows"]
    assert last[1]["a1"] == pytest.approx(6.0) and last[3]["a1"] == pytest.approx(20.0)


def test_a_run_at_time_scale_zero_puts_actual_times_on_a_wall_axis() -> None:
    records = [
        _dispatch(10.0),
        _start(10.0, "01_A", 1, 0.0, 5.0, scale=0.0),
        _end(10.002, "01_A"),
        _dispatch(10.01),
        _start(10.01, "02_B", 2, 20.0, 3.0, scale=0.0),
        _end(10.013, "02_B"),
    ]
    view = fold({}, records).gantt_json()
    assert view["axis"] == "wall"
    a, b = view["rows"]
    assert (a["a0"], a["a1"]) == pytest.approx((0.0, 0.002))
    assert (b["a0"], b["a1"]) == pytest.approx((0.01, 0.013))
    # Planned bars: each plan laid after the previous one's planned end (plan seconds).
    assert (a["p0"], a["p1"], b["p0"], b["p1"]) == pytest.approx((0.0, 5.0, 5.0, 8.0))


def test_a_step_started_again_is_a_new_row_and_its_end_closes_the_newest() -> None:
    records = [
        _dispatch(0.0),
        _start(0.0, "01_A", 1, 0.0, 1.0),
        _end(0.05, "01_A", "aborted"),
        _dispatch(0.1),
        _start(0.1, "01_A", 1, 0.0, 1.0),
        _end(0.2, "01_A"),
    ]
    rows = fold({}, records).gantt_json()["rows"]
    assert [(r["outcome"], r["dispatch"]) for r in rows] == [("aborted", 0), ("succeeded", 1)]


def test_a_run_without_temporal_plans_has_no_gantt_and_bad_values_do_not_break_the_fold() -> None:
    assert fold({}, [_dispatch(0.0)]).gantt_json() is None
    odd = {"kind": "action_started", "path": f"{PLAN}/X", "time": "soon", "planned_start": None}
    rows = fold({}, [odd, {"kind": "action_ended", "path": "/nowhere"}]).gantt_json()
    assert rows is not None and rows["rows"][0]["planned_duration"] == 0.0


def test_copies_of_the_view_do_not_share_the_timeline() -> None:
    model = ViewModel()
    for record in _scaled_run()[:3]:
        model.apply(record)
    copy = model.copy()
    model.apply(_end(100.5, "01_A"))
    assert copy.timeline.actions[0].ended is None
    assert model.timeline.actions[0].ended == 100.5


def test_the_timeline_keeps_a_bounded_number_of_rows() -> None:
    timeline = Timeline()
    timeline.container_started(PLAN)
    for n in range(MAX_ACTIONS + 10):
        timeline.started(f"{PLAN}/{n:05d}_A", _start(float(n), f"{n:05d}_A", n, n, 1.0), 1)
    view = gantt(timeline, None)
    assert view is not None and len(view["rows"]) == MAX_ACTIONS
    assert view["rows"][0]["index"] == 10


def test_a_step_whose_end_event_is_missing_ends_with_its_state() -> None:
    records = [
        _dispatch(0.0),
        _start(0.0, "01_A", 1, 0.0, 1.0),
        {"kind": "container_terminated", "path": f"{PLAN}/01_A", "time": 0.3, "outcome": "aborted"},
    ]
    (row,) = fold({}, records).gantt_json()["rows"]
    assert (row["outcome"], row["running"], row["a1"]) == ("aborted", False, pytest.approx(3.0))


def test_steps_running_when_a_run_was_killed_end_as_interrupted_when_it_resumes() -> None:
    records = [
        {"kind": "container_started", "path": "/ROOT", "time": 0.0},
        _dispatch(0.0),
        _start(0.0, "01_A", 1, 0.0, 5.0),
        _start(0.0, "02_B", 2, 0.0, 1.0),
        _end(0.1, "02_B"),
        {"kind": "resumed"},
        {"kind": "container_started", "path": "/ROOT", "time": 50.0},
        _dispatch(50.0),
        _start(50.0, "03_A", 3, 0.0, 5.0),
    ]
    structure = {"path": "/ROOT", "label": "ROOT", "children": []}
    rows = fold({"structure": structure}, records).gantt_json()["rows"]
    assert [(r["index"], r["outcome"]) for r in rows] == [
        (1, "interrupted"),
        (2, "succeeded"),
        (3, "running"),
    ]
    assert rows[0]["a1"] == pytest.approx(1.0)  # ends when the killed run was last seen
