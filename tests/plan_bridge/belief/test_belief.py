"""The belief state."""

from __future__ import annotations

import pytest

from plan_bridge.belief import Belief, normalise_observations


def test_apply_deletes_before_adding() -> None:
    world = Belief(["(at r a)"])
    world.apply(adds=[("at", "r", "a")], deletes=[("at", "r", "a")])
    assert world.holds("(at r a)")


def test_observe_returns_only_the_changes() -> None:
    world = Belief(["(at r a)", "(free r)"])
    changed = world.observe(
        [(("at", "r", "a"), False), (("free", "r"), True), (("at", "r", "b"), True)]
    )
    assert changed == [(("at", "r", "a"), False), (("at", "r", "b"), True)]
    assert world.facts == {("free", "r"), ("at", "r", "b")}


def test_observations_accept_mappings_pairs_and_text() -> None:
    assert normalise_observations({"(at r a)": True}) == [(("at", "r", "a"), True)]
    assert normalise_observations([(("at", "r", "a"), False)]) == [(("at", "r", "a"), False)]
    assert normalise_observations(None) == []


@pytest.mark.parametrize("bad", [["(at r a)"], [("(at r a)", "yes")], 5])
def test_malformed_observations_are_rejected_with_the_expected_shape(bad: object) -> None:
    with pytest.raises((ValueError, TypeError)):
        normalise_observations(bad)


def test_a_listener_added_as_a_bound_method_is_removed_by_the_same_expression() -> None:
    class Watcher:
        calls = 0

        def poke(self) -> None:
            self.calls += 1

    belief, watcher = Belief(), Watcher()
    belief.add_listener(watcher.poke)
    belief.apply([("a",)], [])
    belief.remove_listener(watcher.poke)  # a new bound method object, equal to the first
    belief.apply([("b",)], [])
    assert watcher.calls == 1
