"""Journal structure records (each machine once, when it starts), checkpoint changes,
and the crash-safe repair of a torn last line."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

import smach
from smach.introspection.compact import compact, expand, structure_of
from smach.introspection.delta import SAME, diff, patch
from smach.introspection.fidelity import journal_problems
from smach.introspection.journal import (
    FULL_EVERY,
    Journal,
    drop_torn_line,
    read_journal,
    read_states,
)
from smach.introspection.model import fold, graft
from smach.introspection.structure import snapshot
from smach.testing import ScriptedState


def machine(labels: list[str]) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["done"])
    for i, label in enumerate(labels):
        following = labels[i + 1] if i + 1 < len(labels) else "done"
        sm.add(label, ScriptedState(["done"]), transitions={"done": following})
    return sm


class Replanner(smach.Wrapper):
    """Runs a new machine at the same path each time round, like an executive's plans."""

    def __init__(self, plans: list[list[str]]) -> None:
        super().__init__(outcomes=["done"])
        self.plans = plans
        self.add("PLAN", machine(plans[0]))

    def run(self, child: smach.State, label: str) -> str:
        outcome = "done"
        for n, labels in enumerate(self.plans):
            if n:  # a new machine where the last one was
                plan = machine(labels)
                self.replace_child("PLAN", plan, self._child)
                self._child = plan
                self.compile_children()
            outcome = self.run_child()
            self.run_child()  # the same machine again: no new structure
        return outcome


def run_replanner(path: Path, plans: list[list[str]]) -> list[dict[str, Any]]:
    root = smach.StateMachine(outcomes=["done"])
    root.add("EXEC", Replanner(plans), transitions={"done": "done"})
    with Journal(path, root):
        root.execute()
    return read_journal(path)[1]


def test_a_machine_replaced_at_the_same_path_has_its_own_structure_written_when_it_starts(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.jsonl"
    records = run_replanner(path, [["S01", "S02"], ["S03", "S04"], ["S05"]])
    structures = [(n, r) for n, r in enumerate(records) if r["kind"] == "structure"]
    # The first machine is in the header; each later one once, just before it starts.
    assert len(structures) == 2
    for n, record in structures:
        assert record["path"] == "/ROOT/EXEC/PLAN"
        assert records[n + 1]["kind"] == "container_started"
        assert records[n + 1]["path"] == record["path"]
        assert records[n + 1]["time"] == record["time"]
    labels = [[c["label"] for c in structure_of(r)["children"]] for _, r in structures]
    assert labels == [["S03", "S04"], ["S05"]]
    assert journal_problems(path) == []


def test_replay_draws_the_machine_that_ran_at_each_moment(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    records = run_replanner(path, [["S01"], ["S02"]])
    header, _ = read_journal(path)
    first_s02 = next(n for n, r in enumerate(records) if r.get("path", "").endswith("/S02"))
    before = fold(header, records, first_s02 - 2)
    after = fold(header, records, first_s02 + 1)
    plan_before = before.structure["children"][0]["children"][0]
    plan_after = after.structure["children"][0]["children"][0]
    assert [c["label"] for c in plan_before["children"]] == ["S01"]
    assert [c["label"] for c in plan_after["children"]] == ["S02"]
    assert "/ROOT/EXEC/PLAN/S02" in after.active


def test_a_nested_machine_that_runs_many_times_writes_no_structure(tmp_path: Path) -> None:
    inner = machine(["A", "B"])
    root = smach.Iterator(
        outcomes=["done"], it=range(5), it_label="i", input_keys=[], output_keys=[],
        exhausted_outcome="done",
    )  # fmt: skip
    root.set_contained_state("BODY", inner, loop_outcomes=["done"])
    path = tmp_path / "loop.jsonl"
    with Journal(path, root) as journal:
        root.execute()
    _, records = read_journal(path)
    assert not [r for r in records if r["kind"] == "structure"]
    assert journal.structures_written == 0
    assert journal_problems(path) == []


def test_graft_replaces_one_subtree_and_leaves_the_old_tree_unchanged() -> None:
    tree = {"path": "/R", "children": [{"path": "/R/P", "children": [{"path": "/R/P/A"}]}]}
    new = graft(tree, {"path": "/R/P", "children": [{"path": "/R/P/B"}]}, "/R/P")
    assert new["children"][0]["children"] == [{"path": "/R/P/B"}]
    assert tree["children"][0]["children"] == [{"path": "/R/P/A"}]
    assert graft(tree, {"path": "/R"}, "/R") == {"path": "/R"}
    added = graft(tree, {"path": "/R/Q"}, "/R/Q")
    assert [c["path"] for c in added["children"]] == ["/R/P", "/R/Q"]


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.text(max_size=5),
    lambda children: (
        st.lists(children, max_size=6) | st.dictionaries(st.text(max_size=3), children, max_size=5)
    ),
    max_leaves=30,
)


@settings(max_examples=300, deadline=None)
@given(json_values, json_values)
def test_patch_of_diff_gives_the_new_value(old: Any, new: Any) -> None:
    change = diff(old, new)
    assert patch(old, change) == new
    assert json.loads(json.dumps(change)) == change  # plain JSON
    if old == new and type(old) is type(new):
        assert change is SAME


def test_a_sorted_fact_list_changes_by_what_it_lost_and_gained() -> None:
    old = sorted(f"(at r{i} room{i})" for i in range(200))
    new = sorted([*old[:50], *old[51:], "(at r0 kitchen)"])
    change = diff(old, new)
    assert change == {"set": [[old[50]], ["(at r0 kitchen)"]]}
    assert patch(old, change) == new


def test_states_are_written_as_changes_and_read_back_whole(tmp_path: Path) -> None:
    path = tmp_path / "states.jsonl"
    facts = [f"fact {i:03d}" for i in range(300)]
    written = []
    with Journal(path) as journal:
        for step in range(FULL_EVERY + 5):
            facts = sorted({*facts[1:], f"done {step:03d}"})
            state = {"facts": facts, "step": step, "plan": [f"s{j}" for j in range(step, 150)]}
            journal.write_state("checkpoint", state=state, world=None)
            written.append({"kind": "checkpoint", "state": state, "world": None})
    _, records = read_journal(path)
    kinds = ["whole" if "whole" in r else "change" for r in records]
    assert kinds[0] == "whole" and kinds[FULL_EVERY] == "whole"
    assert kinds.count("whole") == 2
    assert read_states(records, "checkpoint") == written
    sizes = [len(json.dumps(r)) for r in records]
    assert max(sizes[1:FULL_EVERY]) * 20 < sizes[0]  # a change is a small part of the whole


def test_records_written_whole_by_older_versions_are_read_as_they_are() -> None:
    old = [{"kind": "checkpoint", "state": {"a": 1}, "world": None}]
    assert read_states(old, "checkpoint") == old


def test_a_torn_last_line_is_cut_in_place(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    complete = b"".join(b'{"n": %d}\n' % i for i in range(20_000))
    path.write_bytes(complete + b'{"n": 20000, "tor')
    inode = os.stat(path).st_ino
    drop_torn_line(path)
    assert path.read_bytes() == complete
    assert os.stat(path).st_ino == inode  # the same file: nothing was rewritten


def test_a_file_of_one_torn_line_becomes_empty_and_a_missing_file_is_left_alone(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.jsonl"
    path.write_bytes(b"x" * 200_000)
    drop_torn_line(path)
    assert path.read_bytes() == b""
    drop_torn_line(tmp_path / "missing.jsonl")
    assert not (tmp_path / "missing.jsonl").exists()


def sorted_edges(tree: dict[str, Any]) -> dict[str, Any]:
    out = dict(tree)
    if "edges" in out:
        out["edges"] = sorted(out["edges"], key=lambda e: json.dumps(e, sort_keys=True))
    if "children" in out:
        out["children"] = [sorted_edges(c) for c in out["children"]]
    return out


def test_a_compact_structure_expands_to_the_same_tree_and_is_small() -> None:
    from viewer_machines import big_machine, demo_machine

    for machine in (big_machine(), demo_machine()[0], machine_of_steps(300)):
        tree = snapshot(machine).to_dict()
        data = compact(tree)
        assert sorted_edges(expand(json.loads(json.dumps(data)), tree["path"])) == sorted_edges(
            tree
        )
    tree = snapshot(machine_of_steps(300)).to_dict()
    assert len(json.dumps(compact(tree))) * 10 < len(json.dumps(tree))
    assert structure_of({"kind": "structure", "structure": tree}) == tree


def machine_of_steps(n: int) -> smach.StateMachine:
    """A chain of n identical nested steps, like a compiled plan."""
    sm = smach.StateMachine(outcomes=["done", "failed"])
    for i in range(n):
        step = smach.StateMachine(outcomes=["ok", "failed"])
        step.add("TRY", ScriptedState(["ok", "failed"]), transitions={"ok": "CHECK"})
        step.add("CHECK", ScriptedState(["ok", "failed"]))
        following = f"S{i + 1:04d}" if i + 1 < n else "done"
        sm.add(f"S{i:04d}", step, transitions={"ok": following})
    return sm
