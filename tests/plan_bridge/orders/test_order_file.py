"""Orders files: orders written out, windows drawn from the seed, Poisson streams, errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.orders.order_file import OrderFileError, load_orders, parse_orders


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "orders.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_list_of_orders_is_read_in_arrival_order_with_default_ids(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "- at: 30\n  goal: (lies p1 annex)\n"
        "- at: 5\n  goal: '(lies  p2 west)'\n  priority: 2\n  deadline: 100\n",
    )
    orders = load_orders(path).draw(seed=0)
    assert [(o.id, o.at, o.goal) for o in orders] == [
        ("o2", 5.0, "(lies p2 west)"),
        ("o1", 30.0, "(lies p1 annex)"),
    ]
    assert (orders[0].priority, orders[0].deadline) == (2, 100.0)
    assert orders[0].origin == f"{path}:3"


def test_a_window_is_drawn_from_the_seed_and_within_sets_the_deadline(tmp_path: Path) -> None:
    path = write(tmp_path, "orders:\n  - id: a\n    at: [10, 50]\n    goal: g\n    within: 20\n")
    schedule = load_orders(path)
    first, again, other = (schedule.draw(seed)[0] for seed in (1, 1, 2))
    assert first == again
    assert 10 <= first.at <= 50 and first.at != other.at
    assert first.deadline == pytest.approx(first.at + 20)


def test_a_stream_draws_poisson_arrivals_within_its_hours_from_the_seed(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "streams:\n"
        "  - rate_per_hour: 60\n    start: 600\n    until: 4200\n"
        "    goals: [fetch, deliver, never]\n    weights: [1, 1, 0]\n    id: day\n",
    )
    schedule = load_orders(path)
    orders = schedule.draw(seed=7)
    assert orders == schedule.draw(seed=7)
    assert orders != schedule.draw(seed=8)
    # 60 an hour for one hour: Poisson, so about 60 (the seed fixes the number).
    assert 35 <= len(orders) <= 90
    assert all(600 < o.at <= 4200 for o in orders)
    assert [o.id for o in orders[:3]] == ["day-1", "day-2", "day-3"]
    assert {o.goal for o in orders} == {"fetch", "deliver"}


def test_two_streams_of_one_file_draw_apart(tmp_path: Path) -> None:
    stream = "  - rate_per_hour: 30\n    until: 3600\n    goals: [g]\n"
    orders = load_orders(write(tmp_path, "streams:\n" + stream + stream)).draw(seed=3)
    first = sorted(o.at for o in orders if o.id.startswith("stream-"))
    second = sorted(o.at for o in orders if o.id.startswith("stream2-"))
    assert first and second and first != second


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("- at: 3\n", r"orders.yaml:1: goal: must be atoms"),
        ("- goal: g\n", r"orders.yaml:1: the order has no at:"),
        ("- at: -1\n  goal: g\n", r"orders.yaml:1: at: must be seconds >= 0"),
        ("- at: [9, 2]\n  goal: g\n", r"the window's start is after its end"),
        ("- at: 1\n  goal: g\n  prio: 2\n", r"unknown key 'prio' \(did you mean priority\?"),
        ("- at: 1\n  goal: g\n  priority: high\n", r"priority: must be an integer"),
        ("- at: 1\n  goal: g\n  deadline: 9\n  within: 3\n", r"deadline: or within:, not both"),
        ("ordres: []\n", r"unknown key 'ordres' \(did you mean orders\?"),
        ("streams:\n  - until: 9\n    goals: [g]\n", r"rate_per_hour: must be a number > 0"),
        (
            "streams:\n  - rate_per_hour: 1\n    until: 9\n    goals: [g, h]\n    weights: [1]\n",
            r"weights: must be 2 numbers",
        ),
        ("42\n", r"an orders file is a YAML list"),
    ],
)
def test_a_bad_orders_file_is_refused_naming_the_line_and_what_is_allowed(
    tmp_path: Path, text: str, message: str
) -> None:
    with pytest.raises(OrderFileError, match=message):
        load_orders(write(tmp_path, text))


def test_an_id_used_twice_is_refused_naming_both_places() -> None:
    schedule = parse_orders(
        [{"id": "x", "at": 1, "goal": "g"}, {"id": "x", "at": 2, "goal": "h"}], "f.yaml", {}
    )
    with pytest.raises(OrderFileError, match=r"order id 'x' is used twice"):
        schedule.draw(seed=0)


def test_a_missing_file_is_an_error_naming_it(tmp_path: Path) -> None:
    with pytest.raises(OrderFileError, match=r"nowhere.yaml: cannot read the orders file"):
        load_orders(tmp_path / "nowhere.yaml")
