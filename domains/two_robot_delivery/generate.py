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
import sys
from collections.abc import Sequence

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
        init += [f"(connected {a} {b})", f"(connected {b} {a})"]
        init += [f"(passable {a} {b})", f"(passable {b} {a})"]
    problem = name or f"deliver-{items}x2-s{seed}"
    lines = [
        f"; {items} item(s) per robot (generate.py --items {items} --seed {seed})",
        f"(define (problem {problem})",
        "  (:domain two-robot-delivery)",
        "  (:objects",
        f"    {' '.join(ROBOTS)} - robot",
        f"    {' '.join(ROOMS)} - room",
        f"    {' '.join(objects)} - item)",
        "  (:init",
        *(f"    {fact}" for fact in init),
        "  )",
        "  (:goal (and",
        *(f"    {fact}" for fact in goal),
        "  )))",
    ]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--items", type=int, default=2, help="items per robot (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="chooses the destinations (default 0)")
    parser.add_argument("--name", help="problem name (default deliver-Nx2-sS)")
    args = parser.parse_args(argv)
    try:
        text = generate(args.items, args.seed, args.name)
    except ValueError as exc:
        parser.error(str(exc))
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
