"""Generate two-robot delivery problems: N items per robot, destinations by seed.

The building is the same in every problem: the office and the lab, two halls
joined by a corridor, and a storeroom off each hall. Robot r1 (a manipulator)
fetches kitchen things from storage-a, robot r2 (a tray robot) parcels from
storage-b; each item goes to the office or the lab::

    python domains/two_robot_delivery/generate.py --items 6 --seed 4 > p06.pddl
"""

from __future__ import annotations

import argparse
import random
from collections.abc import Sequence

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem

ROOMS = ("office", "lab", "hall-west", "hall-east", "corridor", "storage-a", "storage-b")
#: Doors (both ways).
DOORS = (
    ("office", "hall-west"),
    ("lab", "hall-east"),
    ("office", "lab"),
    ("hall-west", "corridor"),
    ("corridor", "hall-east"),
    ("hall-west", "storage-a"),
    ("hall-east", "storage-b"),
)
#: robot -> (start room, storeroom, item kinds)
ROBOTS = {
    "r1": ("office", "storage-a", ("cup", "mug", "plate", "bowl", "glass")),
    "r2": ("lab", "storage-b", ("parcel", "letter", "box", "binder", "folder")),
}
DESTINATIONS = ("office", "lab")


def generate(items: int, seed: int, name: str | None = None) -> str:
    """The PDDL text of a problem with ``items`` items per robot."""
    if items < 1:
        raise ValueError(f"--items must be >= 1, got {items}")
    rng = random.Random(seed)
    objects: list[str] = []
    init: list[str] = []
    goal: list[str] = []
    for robot, (start, store, kinds) in ROBOTS.items():
        init += [f"(at {robot} {start})", f"(hand-empty {robot})"]
        for n in range(items):
            item = f"{kinds[n % len(kinds)]}{n + 1}"
            objects.append(item)
            init += [f"(item-at {item} {store})", f"(suits {robot} {item})"]
            goal.append(f"(item-at {item} {rng.choice(DESTINATIONS)})")
    for a, b in DOORS:
        init += both_ways(a, b, "connected", "passable")
    return pddl_problem(
        name or f"deliver-{items}x2-s{seed}",
        "two-robot-delivery",
        objects=[
            f"{' '.join(ROBOTS)} - robot",
            f"{' '.join(ROOMS)} - room",
            f"{' '.join(objects)} - item",
        ],
        init=init,
        goal=goal,
        comment=f"{items} item(s) per robot (generate.py --items {items} --seed {seed})",
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--items", type=int, default=2, help="items per robot (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="chooses the destinations (default 0)")
    parser.add_argument("--name", help="problem name (default deliver-Nx2-sS)")
    return generator_main(parser, lambda args: generate(args.items, args.seed, args.name), argv)


if __name__ == "__main__":
    raise SystemExit(main())
