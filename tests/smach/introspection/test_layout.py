"""The graph's layout: edge labels never overlap, whatever the machine."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from viewer_machines import big_machine, chain_machine, demo_machine

import smach
from smach.introspection.layout import Layout, label_box, layout
from smach.introspection.structure import StateNode, snapshot
from smach.testing import ScriptedState

DOMAINS = Path(__file__).parents[3] / "domains"


def overlapping_labels(lay: Layout) -> list[tuple[str, str]]:
    boxes = [(f"{e.container}:{e.source}->{e.outcome}", label_box(e)) for e in lay.edges]
    return [
        (a, b)
        for (a, p), (b, q) in itertools.combinations(boxes, 2)
        if p[0] < q[2] - 0.01 and q[0] < p[2] - 0.01 and p[1] < q[3] - 0.01 and q[1] < p[3] - 0.01
    ]


def fan_machine() -> smach.StateMachine:
    """Every state can end the machine four ways: many labels meet at the outcomes."""
    outcomes = ["done", "failed", "preempted", "invalid"]
    sm = smach.StateMachine(outcomes=outcomes)
    for i in range(8):
        following = f"S{i + 1}" if i < 7 else "done"
        sm.add(
            f"S{i}",
            ScriptedState(outcomes),
            transitions={"done": following, "failed": "failed", "invalid": "S0"},
        )
    return sm


@pytest.mark.parametrize(
    "build",
    [
        lambda: demo_machine()[0],
        big_machine,
        lambda: chain_machine(40),
        fan_machine,
    ],
    ids=["demo", "big", "chain", "fan"],
)
def test_no_two_edge_labels_overlap(build: object) -> None:
    root = snapshot(build())  # type: ignore[operator]
    assert overlapping_labels(layout(root)) == []


def test_no_two_edge_labels_of_a_planned_mission_overlap(tmp_path: Path) -> None:
    from plan_bridge.cli import main
    from smach.introspection.compact import structure_of
    from smach.introspection.journal import read_journal
    from smach.introspection.model import graft

    journal = tmp_path / "run.jsonl"
    main(["run", str(DOMAINS / "table_clearing"), "--seed", "1", "--journal", str(journal),
          "--quiet"])  # fmt: skip
    header, records = read_journal(journal)
    tree = header["structure"]
    for record in records:
        if record["kind"] == "structure":
            tree = graft(tree, structure_of(record), record["path"])
            assert overlapping_labels(layout(StateNode.from_dict(tree))) == []


def ends(d: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """The first and last point of an SVG path ``M x,y ... x,y``."""
    tokens = d.split(" ")
    first = tokens[0].lstrip("M").split(",")
    last = tokens[-1].lstrip("CL").split(",")
    return (float(first[0]), float(first[1])), (float(last[0]), float(last[1]))


def test_edges_leave_and_arrive_where_their_kind_says() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("A", ScriptedState(["go"]), transitions={"go": "B"})
    sm.add(
        "B",
        ScriptedState(["again", "back", "go"]),
        transitions={"again": "B", "back": "A", "go": "C"},
    )
    sm.add("C", ScriptedState(["go"]), transitions={"go": "done"})
    lay = layout(snapshot(sm))
    box = {s.path: s for s in lay.shapes}
    a, b, c = box["/ROOT/A"], box["/ROOT/B"], box["/ROOT/C"]
    root, pill = box["/ROOT"], box["/ROOT:done"]
    edge = {(e.source, e.outcome): e for e in lay.edges}

    # Forward: from the bottom of the source to the middle of the top of the target.
    (sx, sy), (tx, ty) = ends(edge["A", "go"].d)
    assert a.x < sx < a.x + a.w and sy == pytest.approx(a.y + a.h, abs=0.05)
    assert (tx, ty) == pytest.approx((b.x + b.w / 2, b.y), abs=0.05)
    # Into an outcome: the top of its pill.
    (_, _), (tx, ty) = ends(edge["C", "go"].d)
    assert (tx, ty) == pytest.approx((pill.x + pill.w / 2, pill.y), abs=0.05)
    # A loop and a back edge: from the right-hand side of the source.
    for outcome in ("again", "back"):
        (sx, _), _ = ends(edge["B", outcome].d)
        assert sx == pytest.approx(b.x + b.w, abs=0.05)
    (_, _), (tx, ty) = ends(edge["B", "back"].d)
    assert tx == pytest.approx(a.x + a.w, abs=0.05) and a.y < ty < a.y + a.h
    # The container is wide enough for the labels of the edges around the right side.
    assert all(e.label_x < root.x + root.w for e in lay.edges)
    assert c.y > b.y > a.y
