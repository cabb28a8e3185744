"""Generate door_opening problems of any size (prints PDDL to stdout).

    python domains/door_opening/generate.py --rows 4 --cols 4 --doors 18 --seed 2 > p.pddl

Rooms form a ``--rows`` x ``--cols`` grid; neighbouring rooms are joined either by a
door or by an open passage (``--doors`` of the joints, chosen at random, are doors;
the rest are passages). The robot starts in one corner and must reach the opposite
corner.
"""

from __future__ import annotations

import argparse
import random
import sys
from collections.abc import Sequence

from plan_bridge.missions.problem_writer import both_ways, generator_main, pddl_problem


def room(row: int, col: int) -> str:
    return f"room-{row}-{col}"


def problem_text(*, rows: int, cols: int, doors: int | None, seed: int) -> str:
    if rows < 1 or cols < 1 or rows * cols < 2:
        raise ValueError("need --rows >= 1, --cols >= 1 and at least two rooms")
    rng = random.Random(seed)
    joints = [
        (room(r, c), room(r + dr, c + dc))
        for r in range(1, rows + 1)
        for c in range(1, cols + 1)
        for dr, dc in ((0, 1), (1, 0))
        if r + dr <= rows and c + dc <= cols
    ]
    count = len(joints) if doors is None else max(0, min(doors, len(joints)))
    with_doors = set(rng.sample(range(len(joints)), count))
    init = [f"(at pr2 {room(1, 1)})"]
    door_names = []
    for i, (a, b) in enumerate(joints):
        if i in with_doors:
            door = f"door-{a.removeprefix('room-')}-{b.removeprefix('room-')}"
            door_names.append(door)
            init += [
                *both_ways(a, b, f"door-between {door}"),
                f"(door-closed {door})",
                f"(unlocked {door})",
            ]
        else:
            init += both_ways(a, b, "passage")
    rooms = [room(r, c) for r in range(1, rows + 1) for c in range(1, cols + 1)]
    objects = ["pr2 - robot", f"{' '.join(rooms)} - room"]
    if door_names:
        objects.append(f"{' '.join(door_names)} - door")
    return pddl_problem(
        f"door-opening-{rows}x{cols}-s{seed}",
        "door-opening",
        objects=objects,
        init=init,
        goal=[f"(at pr2 {room(rows, cols)})"],
        comment=f"generated: --rows {rows} --cols {cols} --doors {count} --seed {seed}",
        compact=True,
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--rows", type=int, default=3)
    parser.add_argument("--cols", type=int, default=3)
    parser.add_argument("--doors", type=int, default=None, help="joints with a door (default all)")
    parser.add_argument("--seed", type=int, default=0)
    return generator_main(
        parser,
        lambda args: problem_text(rows=args.rows, cols=args.cols, doors=args.doors, seed=args.seed),
        argv,
    )


if __name__ == "__main__":
    sys.exit(main())
