"""Generate recharge problems of any size (prints PDDL to stdout).

    python domains/recharge/generate.py --rooms 10 --items 4 --seed 1 > problem.pddl

Rooms form a ring (``room1`` ... ``roomN``) with ``--chords`` extra corridors across
it; the charger is in ``room1``. Each of ``--items`` items must be carried from one
random room to another.
"""

from __future__ import annotations

import argparse
import random
import sys
from collections.abc import Sequence

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem


def problem_text(*, rooms: int, items: int, chords: int, seed: int) -> str:
    if rooms < 2 or items < 1 or chords < 0:
        raise ValueError("need --rooms >= 2, --items >= 1, --chords >= 0")
    rng = random.Random(seed)
    names = [f"room{i}" for i in range(1, rooms + 1)]
    edges = {tuple(sorted((names[i], names[(i + 1) % rooms]))) for i in range(rooms)}
    candidates = [
        (a, b)
        for i, a in enumerate(names)
        for b in names[i + 2 :]
        if tuple(sorted((a, b))) not in edges
    ]
    rng.shuffle(candidates)
    edges |= {tuple(sorted(c)) for c in candidates[:chords]}
    item_names = [f"item{i}" for i in range(1, items + 1)]
    init = [f"(at pr2 {rng.choice(names)})", "(hand-empty pr2)", "(battery-ok pr2)"]
    init += ["(unplugged pr2)", "(charger-at room1)"]
    for a, b in sorted(edges):
        init += both_ways(a, b, "connected")
    goal = []
    for item in item_names:
        source, target = rng.sample(names, 2)
        init.append(f"(item-at {item} {source})")
        goal.append(f"(item-at {item} {target})")
    return pddl_problem(
        f"recharge-r{rooms}-i{items}-s{seed}",
        "recharge",
        objects=[f"pr2 - robot {' '.join(names)} - room {' '.join(item_names)} - item"],
        init=init,
        goal=goal,
        comment=f"generated: --rooms {rooms} --items {items} --chords {chords} --seed {seed}",
        compact=True,
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--rooms", type=int, default=8)
    parser.add_argument("--items", type=int, default=3)
    parser.add_argument(
        "--chords", type=int, default=None, help="extra corridors (default rooms/3)"
    )
    parser.add_argument("--seed", type=int, default=0)
    return generator_main(
        parser,
        lambda args: problem_text(
            rooms=args.rooms,
            items=args.items,
            chords=args.chords if args.chords is not None else args.rooms // 3,
            seed=args.seed,
        ),
        argv,
    )


if __name__ == "__main__":
    sys.exit(main())
