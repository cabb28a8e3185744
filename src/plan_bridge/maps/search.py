"""Where to look for an object the belief has lost: the likely places first.

An object is **lost** when a robot looked where it was believed and did not see it
(:mod:`plan_bridge.belief.whereabouts`): the belief has it nowhere and says where it
is not. The task of a goal that needs a lost object gives the planner the places it may
be in, ``(may-hold PLACE OBJECT)``, and the domain's ``search`` action (look for it
there: the plan assumes it is found; when it is not, the replan looks further).

The places are the object spawns of the map a robot can see into (of open locations,
or closed ones it may open; not chargers), minus those where it was looked for. They are
ranked in **tiers** by how well the location fits the object (:func:`fit`):

2. a location of a category where objects of the same category lie (as the belief has
   them) or where this one lay when the world was loaded;
1. a location of a category that suits the object's kind (:data:`KIND_PLACES`: drinks
   in fridges and on counters and tables, food on tables and counters...);
0. every other place.

The places are looked at in the order of their fit **per metre** (:func:`search_order`):
a place's weight (:data:`TIER_WEIGHT`: 1.5, 1.2, 1 for the tiers 2, 1, 0) over the route
from the nearest robot (plus :data:`NEAR_M`), the greedy order of a search that finds the
object soonest on average. A likely place a short way off comes first; a likely place
across the building may wait for an unlikely one next door, so a search that finds
nothing sweeps the building without going to and fro between tiers. A task holds the
first place of that order for each robot (the planner chooses which robot goes);
when no place is left the object cannot be found: :class:`ObjectNotFoundError` names it
and the places searched.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable, Mapping

from plan_bridge.belief.whereabouts import absences, places_of
from plan_bridge.errors import PlanBridgeError
from plan_bridge.maps.model import WorldModel
from plan_bridge.pddl.task import Fact

#: The weight of a place of each tier of fit in the search order.
TIER_WEIGHT = {2: 1.5, 1: 1.2, 0: 1.0}
#: Metres added to every route in the search order (a place next to the robot is not
#: infinitely better than one two metres off).
NEAR_M = 2.0

__all__ = [
    "KINDS",
    "KIND_PLACES",
    "NEAR_M",
    "TIER_WEIGHT",
    "ObjectNotFoundError",
    "fit",
    "place_weights",
    "search_order",
    "search_places",
    "search_tiers",
]

#: Object categories (pyrobosim's, and common ones) by kind.
KINDS: dict[str, frozenset[str]] = {
    "drink": frozenset(
        {
            "water",
            "coke",
            "soda",
            "juice",
            "milk",
            "beer",
            "wine",
            "coffee",
            "tea",
            "drink",
            "bottle",
            "can",
            "cup",
            "mug",
        }
    ),
    "food": frozenset(
        {
            "apple",
            "banana",
            "orange",
            "bread",
            "fruit",
            "food",
            "snack",
            "cereal",
            "sandwich",
            "pear",
            "cheese",
            "meal",
            "tray",
        }
    ),
    "medicine": frozenset({"medicine", "pills", "syringe", "bandage", "drug", "vial"}),
    "tool": frozenset({"tool", "wrench", "screwdriver", "hammer", "part", "box", "bolt"}),
}
#: Location categories (pyrobosim's, and common ones) where things of each kind are kept.
KIND_PLACES: dict[str, frozenset[str]] = {
    "drink": frozenset({"fridge", "counter", "table", "shelf", "cabinet"}),
    "food": frozenset({"table", "counter", "fridge", "shelf", "cabinet"}),
    "medicine": frozenset({"cabinet", "shelf", "cart", "counter", "table"}),
    "tool": frozenset({"shelf", "workbench", "bench", "cabinet", "table", "rack"}),
}


class ObjectNotFoundError(PlanBridgeError):
    """A goal's object is in none of the places it may be in."""

    verdict = True
    """The mission ends with this reason (not "no task for the belief")."""

    def __init__(self, item: str, searched: Collection[str]) -> None:
        self.item = item
        self.searched = sorted(searched)
        places = ", ".join(self.searched) or "nowhere"
        super().__init__(
            f"{item} not found: it was not where it was believed, and not in any place it "
            f"may be in (searched {len(self.searched)}: {places})"
        )


def kind_of(category: str) -> str:
    """The kind (``drink``, ``food``...) of an object category, or ``""``."""
    word = category.lower()
    words = {word, *re.split(r"[^a-z]+", word)}
    for kind, categories in KINDS.items():
        if words & categories:
            return kind
    return ""


def fit(model: WorldModel, facts: Iterable[Fact], item: str, place: str) -> int:
    """How well ``place`` (a place name of the map) fits ``item`` (see the module's doc)."""
    info = model.places.get(place)
    if info is None or info.fixture is None:
        return 0
    return _fits(model, list(facts), item).get(model.gates[info.fixture].category.lower(), 0)


def _fits(model: WorldModel, facts: list[Fact], item: str) -> dict[str, int]:
    """Location category -> its fit for ``item`` (missing: 0)."""
    names = {name.lower(): name for name in model.items}
    own = names.get(item, item)
    category = model.item_categories.get(own, "").lower()
    fits: dict[str, int] = dict.fromkeys(KIND_PLACES.get(kind_of(category), ()), 1)
    usual: set[str] = set()
    start = model.items.get(own)
    if start is not None:
        usual.add(start)
    if category:
        at, _ = places_of(facts)
        place_names = {name.lower(): name for name in model.places}
        for other, places in at.items():
            other_name = names.get(other)
            if other_name is None or other_name == own:
                continue
            if model.item_categories.get(other_name, "").lower() == category:
                usual |= {place_names[q] for q in places if q in place_names}
    for spot in usual:
        place = model.places.get(model.aliases.get(spot, spot))
        if place is not None and place.fixture is not None:
            fits[model.gates[place.fixture].category.lower()] = 2
    return fits


def search_places(model: WorldModel, facts: Collection[Fact]) -> list[str]:
    """Every place an object may be looked for at (see the module's doc), sorted."""
    out: list[str] = []
    for name, place in model.places.items():
        if place.fixture is None or not place.spawns:
            continue
        gate = model.gates[place.fixture]
        lower = gate.name.lower()
        if gate.is_charger:
            continue
        if ("isopen", lower) not in facts and ("islocked", lower) in facts:
            continue  # closed and locked: nobody sees inside
        out.append(name)
    return sorted(out)


def search_tiers(model: WorldModel, facts: Collection[Fact], item: str) -> list[list[str]]:
    """The places (lower case) where lost ``item`` may be, not searched yet, in tiers
    of fit, best first (empty: nowhere left)."""
    tiers = _tiered(model, facts, item)
    return [tiers[score] for score in sorted(tiers, reverse=True)]


def _tiered(model: WorldModel, facts: Collection[Fact], item: str) -> dict[int, list[str]]:
    """Fit -> the places (lower case) of that fit not searched yet."""
    searched = set(absences(facts, item))
    fits = _fits(model, list(facts), item)
    tiers: dict[int, list[str]] = {}
    for name in search_places(model, facts):
        if name.lower() in searched:
            continue
        fixture = model.places[name].fixture
        category = model.gates[fixture].category.lower() if fixture else ""
        tiers.setdefault(fits.get(category, 0), []).append(name.lower())
    return tiers


def search_order(
    model: WorldModel, facts: Collection[Fact], item: str, metres: Mapping[str, float]
) -> list[str]:
    """The places (lower case) to look for lost ``item`` at, in order (see the module's
    doc); ``metres``: the route from the nearest robot to each place (lower case; a
    place missing from it cannot be reached and is left out)."""
    weights = place_weights(model, facts, item)
    ranked = [(-weight / (metres[p] + NEAR_M), p) for p, weight in weights.items() if p in metres]
    return [place for _, place in sorted(ranked)]


def place_weights(model: WorldModel, facts: Collection[Fact], item: str) -> dict[str, float]:
    """The places (lower case) where lost ``item`` may be, not searched yet, and their
    weights in the search order (:data:`TIER_WEIGHT` of their tier of fit)."""
    return {
        place: TIER_WEIGHT.get(tier, 1.0)
        for tier, places in _tiered(model, facts, item).items()
        for place in places
    }
