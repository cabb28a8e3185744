"""Generate table-clearing problems: N objects spread over the table's zones.

The building is the same in every problem (it is the map the skills and the
scripted baseline know); only the number of objects and where they lie vary::

    python domains/table_clearing/generate.py --objects 20 --seed 7 > p20.pddl
"""

from __future__ import annotations

import argparse
import random
from collections.abc import Sequence

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem

ROBOT = "pr2"
CART = "cart1"
LOCATIONS = (
    "table-n",
    "table-s",
    "doorway",
    "corridor-main",
    "corridor-side",
    "back-hall",
    "kitchen",
)
#: Table zones the objects lie on; the floor places are where dropped objects end up.
TABLE_ZONES = ("zone-n", "zone-mid", "zone-s")
FLOORS = ("floor-n", "floor-s")
REACHES = {
    "table-n": ("zone-n", "zone-mid", "floor-n"),
    "table-s": ("zone-s", "zone-mid", "floor-s"),
}
#: Where the robot walks on its own (both ways): inside the dining room only; the
#: corridors to the kitchen are for the cart run (the robot does not roam the
#: building with an object in its gripper).
ADJACENT = (
    ("table-n", "table-s"),
    ("table-n", "doorway"),
    ("table-s", "doorway"),
)
#: Where the cart fits (both ways): not between the table's sides.
PASSAGES = (
    ("table-n", "doorway"),
    ("table-s", "doorway"),
    ("doorway", "corridor-main"),
    ("corridor-main", "kitchen"),
    ("doorway", "corridor-side"),
    ("corridor-side", "back-hall"),
    ("back-hall", "kitchen"),
)
KINDS = ("cup", "plate", "bowl", "glass", "mug", "fork", "knife", "spoon", "jar", "tray")


def item_names(count: int) -> list[str]:
    return [f"{KINDS[i % len(KINDS)]}{i + 1}" for i in range(count)]


def generate(objects: int, seed: int, name: str | None = None) -> str:
    """The PDDL text of a problem with ``objects`` objects placed by ``seed``."""
    if objects < 1:
        raise ValueError(f"--objects must be >= 1, got {objects}")
    rng = random.Random(seed)
    items = item_names(objects)
    zones = {item: rng.choice(TABLE_ZONES) for item in items}
    init = [f"(robot-at {ROBOT} table-n)", f"(cart-at {CART} table-n)", f"(hand-empty {ROBOT})"]
    for a, b in ADJACENT:
        init += both_ways(a, b, "adjacent")
    for a, b in PASSAGES:
        init += both_ways(a, b, "passage", "clear")
    for location, places in REACHES.items():
        init += [f"(reaches {location} {place})" for place in places]
    init += [f"(item-at {item} {zones[item]})" for item in items]
    goal = [f"(on-cart {item} {CART})" for item in items] + [f"(cart-at {CART} kitchen)"]
    return pddl_problem(
        name or f"clear-table-{objects}-s{seed}",
        "table-clearing",
        objects=[
            f"{ROBOT} - robot",
            f"{CART} - cart",
            f"{' '.join(LOCATIONS)} - location",
            f"{' '.join(TABLE_ZONES + FLOORS)} - spot",
            f"{' '.join(items)} - item",
        ],
        init=init,
        goal=goal,
        comment=f"{objects} objects on the table (generate.py --objects {objects} --seed {seed})",
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=5, help="number of objects (default 5)")
    parser.add_argument("--seed", type=int, default=0, help="where the objects lie (default 0)")
    parser.add_argument("--name", help="problem name (default clear-table-N-sS)")
    return generator_main(parser, lambda args: generate(args.objects, args.seed, args.name), argv)


if __name__ == "__main__":
    raise SystemExit(main())
