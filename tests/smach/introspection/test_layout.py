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
