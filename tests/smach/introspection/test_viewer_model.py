"""The folded view, journal records, exports and the static SVG layout."""

from __future__ import annotations

import json
import threading
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from viewer_machines import big_machine, chain_machine, demo_machine

import smach
from smach.introspection import events as ev
from smach.introspection.export import export_journal, export_view
from smach.introspection.journal import Journal, event_record, read_journal, summarise
from smach.introspection.layout import layout, text_width
from smach.introspection.model import History, active_at, fold
from smach.introspection.render import to_svg
from smach.introspection.structure import snapshot


def _run_demo(tmp_path: Path) -> tuple[Path, smach.StateMachine]:
    sm, hold = demo_machine()
    path = tmp_path / "run.jsonl"
    with Journal(path, sm, header={"title": "demo"}):
        hold["pick"].release("picked")
        hold["arm"].release("done")
        hold["base"].go.set()
        assert sm.execute() == "done"
    return path, sm


def test_event_record_matches_summarised_to_dict() -> None:
    common = {"path": "/ROOT/A", "time": 1.5, "thread": "MainThread"}
    samples = [
        ev.ContainerStarted(**common, container_type="StateMachine", initial_states=("A",)),
        ev.StateEntered(**common, label="A"),
        ev.StateExited(**common, label="A", outcome=None),
        ev.Transition(**common, source="A", outcome="done", target="B"),
        ev.PreemptRequested(**common),
        ev.UserdataWritten(**common, key="k", value={"x": [1, 2, object()]}, writer="A"),
        ev.UserdataWritten(**common, key="nan", value=float("nan"), writer="A"),
        ev.ContainerTerminated(**common, terminal_states=("A",), outcome="done"),
        ev.ErrorRaised(**common, error_type="ValueError", message="x" * 500),
    ]
    for event in samples:
        expected = {k: summarise(v) for k, v in event.to_dict().items()}
        got = event_record(event)
        assert json.dumps(got, default=str)[:80] == json.dumps(expected, default=str)[:80]
        assert got.keys() == expected.keys()
        assert {k: v for k, v in got.items() if k != "value"} == {
            k: v for k, v in expected.items() if k != "value"
        }


@pytest.mark.timeout(30)
def test_fold_of_a_journal_tracks_active_states_outcomes_and_userdata(tmp_path: Path) -> None:
    sm, hold = demo_machine()
    path = tmp_path / "run.jsonl"
    journal = Journal(path, sm)
    runner = threading.Thread(target=sm.execute)
    runner.start()
    assert hold["pick"].started.wait(10)
    journal.flush()  # the writer thread would get there within milliseconds
    header, records = read_journal(path)
    view = fold(header, records)
    assert list(view.active) == ["/ROOT", "/ROOT/FETCH", "/ROOT/FETCH/PICK"]
    assert view.outcomes["/ROOT/INIT"] == "ok"
    assert view.userdata["/ROOT/FETCH"]["n"] == 2
    assert view.writers["/ROOT/FETCH"]["n"] == "NAVIGATE"
    hold["pick"].release("picked")
    assert hold["arm"].started.wait(10) and hold["base"].started.wait(10)
    journal.flush()
    header, records = read_journal(path)
    view = fold(header, records)
    assert {"/ROOT/PAR/ARM", "/ROOT/PAR/BASE"} <= set(view.active)
    assert view.last_edges["/ROOT"] == ["FETCH", "got", "PAR"]
    sm.request_preempt()
    assert hold["base"].started.wait(10)
    hold["base"].go.set()
    runner.join(10)
    journal.close()
    header, records = read_journal(path)
    view = fold(header, records)
    assert view.active == {}
    assert not view.running
    assert view.root_outcome == "failed"
    assert view.outcomes["/ROOT/PAR/ARM"] == "preempted"


def test_history_jumps_agree_with_folding_from_the_start(tmp_path: Path) -> None:
    path, _ = _run_demo(tmp_path)
    header, records = read_journal(path)
    history = History(header, every=4, limit=1000)
    for record in records:
        history.add(record)
    for n in range(len(records) + 1):
        assert history.view_at(n).to_json() == fold(header, records, n).to_json()


def test_history_keeps_a_bounded_number_of_records(tmp_path: Path) -> None:
    path, _ = _run_demo(tmp_path)
    header, records = read_journal(path)
    history = History(header, every=3, limit=10)
    for _ in range(5):
        for record in records:
            history.add(record)
    assert len(history.records) <= 10
    assert history.total == 5 * len(records)
    assert history.view_at(history.total).to_json() == history.model.to_json()
    n = history.total - 2
    expected = history.model.copy()
    assert history.view_at(n).index == n
    assert expected.index == history.total


def test_active_at_time_and_event(tmp_path: Path) -> None:
    path, _ = _run_demo(tmp_path)
    header, records = read_journal(path)
    assert active_at(header, records, event=0).active == {}
    at_end = active_at(header, records, at=1e9)
    assert at_end.index == len(records)
    entered = next(i for i, r in enumerate(records) if r.get("path") == "/ROOT/FETCH/PICK")
    assert "/ROOT/FETCH/PICK" in active_at(header, records, event=entered + 1).active


def test_svg_export_is_valid_xml_with_every_state_and_the_active_ones() -> None:
    sm, _ = demo_machine()
    tree = snapshot(sm)
    text = to_svg(tree, active=["/ROOT/FETCH", "/ROOT/FETCH/PICK"], preempt=["/ROOT/FETCH/PICK"])
    root = ET.fromstring(text)
    paths = {el.get("data-path") for el in root.iter() if el.get("data-path")}
    assert {n.path for n in tree.walk()} <= paths
    ns = "{http://www.w3.org/2000/svg}"
    active = [
        el.get("data-path")
        for el in root.iter(f"{ns}g")
        if "active" in (el.get("class") or "").split()
    ]
    assert set(active) == {"/ROOT/FETCH", "/ROOT/FETCH/PICK"}
    assert "PREEMPT REQUESTED" in text
    assert "<style>" in text  # standalone: carries its stylesheet


def test_layout_boxes_fit_their_labels_and_do_not_overlap() -> None:
    tree = snapshot(big_machine())
    lay = layout(tree)
    states = [s for s in lay.shapes if s.kind == "state"]
    assert len(states) >= 50
    for s in states:
        assert s.w >= text_width(s.label, bold=True)
    for i, a in enumerate(states):
        for b in states[i + 1 :]:
            apart = a.x + a.w <= b.x or b.x + b.w <= a.x or a.y + a.h <= b.y or b.y + b.h <= a.y
            assert apart, (a.path, b.path)
    assert 0.3 < lay.width / lay.height < 4


def test_long_chains_wrap_into_columns() -> None:
    lay = layout(snapshot(chain_machine(1000)))
    assert 0.5 < lay.width / lay.height < 3


def test_collapsed_containers_are_one_box() -> None:
    tree = snapshot(big_machine())
    lay = layout(tree, collapsed=["/ROOT/MISSION"])
    kinds = {s.path: s.kind for s in lay.shapes}
    assert kinds["/ROOT/MISSION"] == "collapsed"
    assert not any(p.startswith("/ROOT/MISSION/") for p in kinds)


@pytest.mark.parametrize("fmt", ["dot", "mermaid", "svg"])
def test_export_of_a_journal_at_a_moment_colours_the_active_states(
    tmp_path: Path, fmt: str
) -> None:
    path, _ = _run_demo(tmp_path)
    _header, records = read_journal(path)
    entered = next(i for i, r in enumerate(records) if r.get("path") == "/ROOT/FETCH/PICK")
    text = export_journal(path, fmt, event=entered + 1)
    if fmt == "dot":
        assert '"/ROOT/FETCH/PICK" [label="PICK", fillcolor="#ffd54f"]' in text
    elif fmt == "mermaid":
        assert "class s_ROOT_FETCH_PICK active" in text
    else:
        assert 'class="node state t-BlockingState d2 active' in text
    final = export_journal(path, fmt)
    assert "#ffd54f" not in final.split("classDef")[0] if fmt == "mermaid" else True


def test_export_view_refuses_unknown_formats_and_missing_structures() -> None:
    model = fold({}, [])
    with pytest.raises(ValueError, match="no structure"):
        export_view(model, "svg")
    sm, _ = demo_machine()
    model = fold({"structure": snapshot(sm).to_dict()}, [])
    with pytest.raises(ValueError, match="unknown export format"):
        export_view(model, "png")


def test_journal_writes_a_structure_record_when_the_tree_grows(tmp_path: Path) -> None:
    from viewer_machines import Trivial

    from smach.introspection.compact import structure_of

    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Trivial(), transitions={"done": "done"})
    path = tmp_path / "grow.jsonl"
    with Journal(path, sm):
        sm.execute()
        with sm:
            smach.StateMachine.add("B", Trivial(), transitions={"done": "done"})
        sm.set_initial_state(["B"])
        sm.execute()
    header, records = read_journal(path)
    kinds = [r["kind"] for r in records]
    assert kinds.count("structure") == 1
    structure = structure_of(records[kinds.index("structure")])
    assert [c["label"] for c in structure["children"]] == ["A", "B"]
    view = fold(header, records)
    assert view.structure_version == 1
