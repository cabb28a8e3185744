"""smach.Sequence: a StateMachine chained by one connector outcome."""

from __future__ import annotations

import pytest
from smach_helpers import Fn, Leaf

import smach


def test_sequence_runs_states_in_order_and_returns_connector_outcome() -> None:
    order: list[str] = []
    seq = smach.Sequence(["succeeded", "aborted"], connector_outcome="succeeded")
    with seq:
        for label in ("A", "B", "C"):
            smach.Sequence.add(
                label,
                Fn(
                    lambda s, ud, label=label: order.append(label) or "succeeded",
                    ["succeeded", "aborted"],
                ),
            )
    assert seq.execute() == "succeeded"
    assert order == ["A", "B", "C"]


def test_sequence_is_a_statemachine() -> None:
    seq = smach.Sequence(["succeeded"], "succeeded")
    assert isinstance(seq, smach.StateMachine)


def test_non_connector_outcome_falls_through_as_container_outcome() -> None:
    last = Leaf(["succeeded"])
    seq = smach.Sequence(["succeeded", "aborted"], connector_outcome="succeeded")
    with seq:
        smach.Sequence.add("A", Leaf(["succeeded", "aborted"], result="aborted"))
        smach.Sequence.add("B", last)
    assert seq.execute() == "aborted"
    assert last.calls == 0


def test_sequence_links_connectors_in_transitions() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    with seq:
        smach.Sequence.add("A", Leaf(["succeeded"]))
        smach.Sequence.add("B", Leaf(["succeeded"]))
    assert seq._transitions["A"]["succeeded"] == "B"
    assert seq._transitions["B"]["succeeded"] is None
    assert ("succeeded", "A", "B") in seq.get_internal_edges()


def test_explicit_transition_overrides_connector() -> None:
    skipped = Leaf(["succeeded"])
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    with seq:
        smach.Sequence.add("A", Leaf(["succeeded"]), transitions={"succeeded": "C"})
        smach.Sequence.add("B", skipped)
        smach.Sequence.add("C", Leaf(["succeeded"]))
    assert seq.execute() == "succeeded"
    assert skipped.calls == 0


def test_explicit_transitions_on_other_outcomes_are_kept() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    with seq:
        smach.Sequence.add("A", Leaf(["succeeded"]))
        smach.Sequence.add(
            "RETRY", Leaf(["succeeded", "retry"], result="succeeded"), transitions={"retry": "A"}
        )
    assert seq._transitions["RETRY"]["retry"] == "A"
    assert seq.execute() == "succeeded"


def test_state_without_connector_outcome_is_rejected() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    with pytest.raises(smach.InvalidStateError), seq:
        smach.Sequence.add("A", Leaf(["done"]))


@pytest.mark.parametrize("connector", ["", None, 3])
def test_invalid_connector_outcome_is_rejected(connector: object) -> None:
    with pytest.raises(smach.InvalidStateError):
        smach.Sequence(["succeeded"], connector_outcome=connector)  # type: ignore[arg-type]


def test_sequence_add_supports_remapping_and_returns_state() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    writer = Fn(
        lambda s, ud: setattr(ud, "out", 1) or "succeeded", ["succeeded"], output_keys=["out"]
    )
    with seq:
        assert smach.Sequence.add("W", writer, remapping={"out": "value"}) is writer
    seq.execute()
    assert seq.userdata.value == 1


def test_sequence_instance_add_works_without_with() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    seq.add("A", Leaf(["succeeded"]))
    seq.add("B", Leaf(["succeeded"]))
    assert seq.execute() == "succeeded"
    assert seq["B"].calls == 1  # type: ignore[attr-defined]


def test_sequence_nested_in_statemachine() -> None:
    seq = smach.Sequence(["succeeded"], connector_outcome="succeeded")
    seq.add("A", Leaf(["succeeded"]))
    sm = smach.StateMachine(["done"])
    sm.add("SEQ", seq, {"succeeded": "done"})
    assert sm.execute() == "done"
