"""Where things are and where they are not: the belief's whereabouts."""

from __future__ import annotations

from plan_bridge.belief import Belief
from plan_bridge.belief.whereabouts import ABSENT, absences, locate, lost


def test_an_object_not_seen_where_it_was_believed_is_lost_and_absent_from_there() -> None:
    belief = Belief([("at", "soda", "desk"), ("at", "robot", "desk")], whereabouts=True)
    belief.observe([(("at", "soda", "desk"), False)])
    assert lost(belief.facts, ["soda"]) == ["soda"]
    assert absences(belief.facts, "soda") == ["desk"]


def test_places_a_lost_object_is_not_seen_at_add_up() -> None:
    belief = Belief([("at", "robot", "desk")], whereabouts=True)
    belief.observe([(("at", "soda", "desk"), False)])
    belief.observe([(("at", "soda", "table"), False)])
    assert absences(belief.facts, "soda") == ["desk", "table"]


def test_an_object_seen_somewhere_is_there_only_and_absent_nowhere() -> None:
    belief = Belief([("at", "soda", "desk"), (ABSENT, "soda", "shelf")], whereabouts=True)
    belief.observe([(("at", "soda", "counter"), True)])
    assert ("at", "soda", "counter") in belief
    assert ("at", "soda", "desk") not in belief
    assert absences(belief.facts, "soda") == []


def test_not_seeing_an_object_believed_elsewhere_leaves_it_there() -> None:
    belief = Belief([("at", "soda", "desk")], whereabouts=True)
    belief.observe([(("at", "soda", "table"), False)])
    assert ("at", "soda", "desk") in belief
    assert absences(belief.facts, "soda") == []


def test_a_held_object_is_not_lost_when_not_seen_at_a_place() -> None:
    facts = {("holding", "robot", "cup")}
    assert locate(facts, [(("at", "cup", "desk"), False)]) == [(("at", "cup", "desk"), False)]


def test_an_object_seen_at_a_place_is_no_longer_held() -> None:
    belief = Belief([("holding", "robot", "cup")], whereabouts=True)
    belief.observe([(("at", "cup", "desk"), True)])
    assert ("holding", "robot", "cup") not in belief


def test_a_new_object_seen_joins_the_belief() -> None:
    belief = Belief([("at", "robot", "desk")], whereabouts=True)
    belief.observe([(("at", "cup0", "desk"), True)])
    assert ("at", "cup0", "desk") in belief


def test_without_whereabouts_the_belief_records_only_what_was_observed() -> None:
    belief = Belief([("at", "soda", "desk")])
    belief.observe([(("at", "soda", "desk"), False), (("at", "soda", "table"), True)])
    assert set(belief.facts) == {("at", "soda", "table")}
