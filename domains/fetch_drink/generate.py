"""Generate fetch_drink problems of any size (prints PDDL to stdout).

    python domains/fetch_drink/generate.py --rooms 12 --drinks 4 --seed 3 > problem.pddl

The home is a random connected graph: ``--rooms`` places besides the kitchen, joined
by a spanning tree of corridors plus ``--loops`` extra corridors (so that a blocked
corridor usually has a detour). Each of ``--drinks`` people wants one drink from the
kitchen fridge, whose drinks stand on ``--shelves`` shelves.
"""

from __future__ import annotations

import argparse
import random
import sys
from collections.abc import Sequence

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem


def corridors(places: Sequence[str], loops: int, rng: random.Random) -> list[tuple[str, str]]:
    """A spanning tree over ``places`` plus ``loops`` extra corridors (undirected)."""
    edges: set[tuple[str, str]] = set()
    for i in range(1, len(places)):
        a, b = places[i], places[rng.randrange(i)]
        edges.add((min(a, b), max(a, b)))
    candidates = [
        (a, b)
        for i, a in enumerate(places)
        for b in places[i + 1 :]
        if (min(a, b), max(a, b)) not in edges
    ]
    rng.shuffle(candidates)
    for a, b in candidates[:loops]:
        edges.add((min(a, b), max(a, b)))
    return sorted(edges)


def problem_text(*, rooms: int, drinks: int, shelves: int, loops: int, seed: int) -> str:
    if rooms < 1 or drinks < 1 or shelves < 1 or loops < 0:
        raise ValueError("need --rooms >= 1, --drinks >= 1, --shelves >= 1, --loops >= 0")
    rng = random.Random(seed)
    places = ["kitchen", *(f"room{i}" for i in range(1, rooms + 1))]
    edges = corridors(places, loops, rng)
    shelf_names = [f"shelf{i}" for i in range(1, shelves + 1)]
    people = [f"person{i}" for i in range(1, drinks + 1)]
    drink_names = [f"drink{i}" for i in range(1, drinks + 1)]
    rooms_only = places[1:]
    init = [f"(at pr2 {rng.choice(rooms_only)})", "(hand-empty pr2)"]
    for a, b in edges:
        init += both_ways(a, b, "connected", "clear")
    init += ["(fridge-in kitchen-fridge kitchen)", "(fridge-closed kitchen-fridge)"]
    init += [f"(shelf-of {s} kitchen-fridge)" for s in shelf_names]
    init += [f"(on {d} {rng.choice(shelf_names)})" for d in drink_names]
    init += [f"(person-at {p} {rng.choice(rooms_only)})" for p in people]
    goal = [f"(served {p} {d})" for p, d in zip(people, drink_names, strict=True)]
    goal.append("(fridge-closed kitchen-fridge)")
    return pddl_problem(
        f"fetch-drink-r{rooms}-d{drinks}-s{seed}",
        "fetch-drink",
        objects=[
            f"pr2 - robot {' '.join(places)} - place kitchen-fridge - fridge",
            f"{' '.join(shelf_names)} - shelf {' '.join(drink_names)} - drink",
            f"{' '.join(people)} - person",
        ],
        init=init,
        goal=goal,
        comment=f"generated: --rooms {rooms} --drinks {drinks} --shelves {shelves} "
        f"--loops {loops} --seed {seed}",
        compact=True,
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--rooms", type=int, default=6, help="places besides the kitchen")
    parser.add_argument("--drinks", type=int, default=2, help="people, each wanting one drink")
    parser.add_argument("--shelves", type=int, default=3, help="shelves of the fridge")
    parser.add_argument("--loops", type=int, default=None, help="extra corridors (default rooms/2)")
    parser.add_argument("--seed", type=int, default=0)
    return generator_main(
        parser,
        lambda args: problem_text(
            rooms=args.rooms,
            drinks=args.drinks,
            shelves=args.shelves,
            loops=args.loops if args.loops is not None else max(1, args.rooms // 2),
            seed=args.seed,
        ),
        argv,
    )


if __name__ == "__main__":
    sys.exit(main())
