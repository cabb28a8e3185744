"""Structure snapshots and their DOT/Mermaid renderings."""

from __future__ import annotations

import json
import shutil
import subprocess

import pytest

import smach
from smach.introspection.structure import StateNode
from smach.testing import ScriptedState


def nested() -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add("START", ScriptedState(["go"]), transitions={"go": "PAR"})
        cc = smach.Concurrence(
            outcomes=["ok", "bad"], default_outcome="bad", outcome_map={"ok": {"L": "x", "R": "y"}}
        )
        with cc:
            smach.Concurrence.add("L", ScriptedState(["x"]))
            smach.Concurrence.add("R", ScriptedState(["y"]))
        smach.StateMachine.add("PAR", cc, transitions={"ok": "done", "bad": "failed"})
    return sm


def test_snapshot_captures_paths_types_edges_and_initial_states() -> None:
    node = smach.snapshot(nested())
    assert node.path == "/ROOT" and node.is_container and node.initial_states == ("START",)
    assert [c.path for c in node.walk()] == [
        "/ROOT",
        "/ROOT/START",
        "/ROOT/PAR",
        "/ROOT/PAR/L",
        "/ROOT/PAR/R",
    ]
    par = node.find("/ROOT/PAR")
    assert par is not None and par.type == "Concurrence"
    assert {(e.source, e.outcome, e.target, e.terminal) for e in par.edges} == {
        ("L", "x", "ok", True),
        ("R", "y", "ok", True),
    }


def test_snapshot_round_trips_through_json() -> None:
    node = smach.snapshot(nested())
    again = StateNode.from_dict(json.loads(json.dumps(node.to_dict())))
    assert again == node


def test_dot_has_clusters_for_containers_and_edges_from_their_outcomes() -> None:
    dot = smach.to_dot(smach.snapshot(nested()), active=["/ROOT/PAR/L"])
    assert 'subgraph "cluster_/ROOT/PAR"' in dot
    assert '"/ROOT/PAR:ok" -> "/ROOT:done" [label="ok"]' in dot
    assert '"/ROOT/START" -> "/ROOT/PAR/L" [label="go", lhead="cluster_/ROOT/PAR"]' in dot
    assert '"/ROOT/PAR/L" [label="L", fillcolor="#ffd54f"]' in dot


def test_dot_frames_an_active_container_in_the_active_colour_and_no_other() -> None:
    dot = smach.to_dot(smach.snapshot(nested()), active=["/ROOT", "/ROOT/PAR", "/ROOT/PAR/L"])
    lines = dot.splitlines()
    par = lines[lines.index('  subgraph "cluster_/ROOT" {') + 1 :]
    frame = next(line for line in par if 'label="PAR (Concurrence)"' in line)
    assert 'color="#f57f17"' in frame and "penwidth" in frame
    idle = smach.to_dot(smach.snapshot(nested()), active=["/ROOT/START"])
    assert 'color="#f57f17"' not in idle


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz is not installed")
def test_dot_output_is_accepted_by_graphviz() -> None:
    result = subprocess.run(
        ["dot", "-Tsvg"],
        input=smach.to_dot(smach.snapshot(nested())),
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr


def test_mermaid_has_composite_states_initial_markers_and_active_class() -> None:
    text = smach.to_mermaid(smach.snapshot(nested()), active=["/ROOT/START"])
    assert text.startswith("stateDiagram-v2")
    assert 'state "PAR (Concurrence)" as s_ROOT_PAR {' in text
    assert "[*] --> s_ROOT_PAR_L" in text and "[*] --> s_ROOT_PAR_R" in text
    assert "s_ROOT_PAR__o_ok --> s_ROOT__o_done : ok" in text
    assert "class s_ROOT_START active" in text


def test_labels_with_odd_characters_give_valid_identifiers() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("PICK-CUP.1", ScriptedState(["done"]))
    text = smach.to_mermaid(smach.snapshot(sm))
    assert "s_ROOT_PICK_CUP_1" in text
