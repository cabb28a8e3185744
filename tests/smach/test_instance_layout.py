"""How many attributes a container instance keeps (a property of first-run speed).

CPython (3.11+) stores up to 29 instance attributes of a class in a shared-key, inline
layout; a 30th gives every instance its own dict, which makes the first run of a freshly
built machine read about twice as much memory (docs/performance.md, smach core). The
containers plan_bridge builds and runs once must stay within that.
"""

from __future__ import annotations

import pytest
from smach_helpers import Leaf

import smach

#: The most attributes CPython keeps shared-key and inline (SHARED_KEYS_MAX_SIZE - 1).
MOST_INLINE_ATTRIBUTES = 29


def _machine() -> smach.StateMachine:
    sm = smach.StateMachine(["done"], input_keys=["x"], output_keys=["x"])
    with sm:
        smach.StateMachine.add("A", Leaf(["next"]), {"next": "B"}, remapping={"x": "x"})
        smach.StateMachine.add("B", Leaf(["done"]))
    return sm


def _sequence() -> smach.Sequence:
    seq = smach.Sequence(["done"], connector_outcome="done")
    with seq:
        smach.Sequence.add("A", Leaf(["done"]))
        smach.Sequence.add("B", Leaf(["done"]))
    return seq


def _iterator() -> smach.Iterator:
    it = smach.Iterator(
        outcomes=["done"],
        input_keys=[],
        output_keys=[],
        it=[1, 2, 3],
        it_label="item",
        exhausted_outcome="done",
    )
    with it:
        smach.Iterator.set_contained_state("BODY", Leaf(["next"]), loop_outcomes=["next"])
    return it


def _concurrence() -> smach.Concurrence:
    cc = smach.Concurrence(["done"], default_outcome="done")
    with cc:
        smach.Concurrence.add("A", Leaf(["done"]))
        smach.Concurrence.add("B", Leaf(["done"]))
    return cc


def _retry() -> smach.Retry:
    return smach.Retry.wrap("BODY", Leaf(["done", "aborted"]), attempts=2)


def _timeout() -> smach.Timeout:
    return smach.Timeout.wrap("BODY", Leaf(["done"]), timeout=5.0)


BUILDERS = {
    "StateMachine": _machine,
    "Sequence": _sequence,
    "Iterator": _iterator,
    "Concurrence": _concurrence,
    "Retry": _retry,
    "Timeout": _timeout,
}


@pytest.mark.parametrize("kind", sorted(BUILDERS))
def test_a_container_keeps_at_most_29_instance_attributes_after_a_logged_run(kind: str) -> None:
    container = BUILDERS[kind]()
    lines: list[str] = []
    smach.set_loggers(lines.append, lines.append, lines.append, lines.append)
    try:
        assert container.execute(smach.UserData()) == "done"
    finally:
        smach.log.restore_default_loggers()
    assert lines, "the run wrote its log lines"
    names = sorted(vars(container))
    assert len(names) <= MOST_INLINE_ATTRIBUTES, f"{kind}: {len(names)} attributes: {names}"


def test_callbacks_registered_on_one_machine_are_not_seen_by_another() -> None:
    first, second = _machine(), _machine()
    seen: list[tuple[str, str]] = []
    first.register_start_cb(lambda ud, states: seen.append(("start", states[0])))
    first.register_transition_cb(lambda ud, states: seen.append(("transition", states[0])))
    first.register_termination_cb(lambda ud, states, outcome: seen.append(("end", outcome)))
    ud = smach.UserData()
    ud.x = 0
    assert second.execute(ud) == "done"
    assert seen == []
    assert first.execute(ud) == "done"
    assert seen[0] == ("start", "A") and seen[-1] == ("end", "done")
    assert ("transition", "B") in seen
