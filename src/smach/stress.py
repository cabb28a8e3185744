"""Random nested machines for stress-testing: every run must end, nothing may leak.

``random_machine(rng)`` builds a random, consistent tree of StateMachine,
Concurrence, Iterator, Sequence, Retry and Timeout containers over leaves that return
random outcomes, sleep (preempt-aware or not), or raise. ``stress(runs, seed)`` runs
many of them, preempting each from another thread at a random moment, and checks
that every run ends within a time bound with a declared outcome or a smach error.
Used by the test suite (small) and ``benchmarks/stress.py`` (large).
"""

from __future__ import annotations

import random
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import smach
from smach.exceptions import SmachError
from smach.state import State
from smach.user_data import UserData

__all__ = ["StressReport", "random_machine", "stress"]

OUTCOMES = ("a", "b", "preempted")


class RandomLeaf(State):
    """Returns a random outcome after an optional delay; may raise or ignore preempts."""

    def __init__(self, rng: random.Random) -> None:
        super().__init__(outcomes=list(OUTCOMES))
        self.delay = rng.choice((0.0, 0.0, 0.001, 0.005, 0.02))
        self.raises = rng.random() < 0.03
        self.deaf = rng.random() < 0.1  # polls nothing: finishes its delay regardless
        self.seed = rng.randrange(1 << 30)
        self.runs = 0

    def execute(self, ud: UserData) -> str:
        self.runs += 1
        rng = random.Random(self.seed + self.runs)
        if self.delay:
            if self.deaf:
                time.sleep(self.delay)
            elif self.sleep(self.delay):
                self.service_preempt()
                return "preempted"
        if self.raises and rng.random() < 0.5:
            raise RuntimeError("random failure")
        return rng.choice(("a", "a", "b"))


def random_machine(rng: random.Random, depth: int = 0, max_depth: int = 3) -> State:
    """A random consistent tree with outcomes ``a``, ``b``, ``preempted``."""
    if depth > 0 and (depth >= max_depth or rng.random() < 0.3):
        return RandomLeaf(rng)
    kind = rng.choice(("sm", "sm", "concurrence", "iterator", "sequence", "retry", "timeout"))
    if kind == "sm":
        sm = smach.StateMachine(outcomes=list(OUTCOMES))
        n = rng.randint(1, 4)
        for i in range(n):
            nxt = f"S{i + 1}" if i + 1 < n else "a"
            # Only forward transitions (plus terminal ones): every run ends.
            sm.add(
                f"S{i}",
                random_machine(rng, depth + 1, max_depth),
                transitions={"a": nxt, "b": rng.choice([nxt, "b"]), "preempted": "preempted"},
            )
        return sm
    if kind == "sequence":
        seq = smach.Sequence(outcomes=list(OUTCOMES), connector_outcome="a")
        for i in range(rng.randint(1, 3)):
            seq.add(f"Q{i}", random_machine(rng, depth + 1, max_depth))
        return seq
    if kind == "concurrence":
        cc = smach.Concurrence(
            outcomes=list(OUTCOMES),
            default_outcome="b",
            outcome_map={"a": {"C0": "a"}, "preempted": {"C0": "preempted"}},
            child_termination_cb=(lambda outcomes: True) if rng.random() < 0.3 else None,
        )
        for i in range(rng.randint(1, 3)):
            cc.add(f"C{i}", random_machine(rng, depth + 1, max_depth))
        return cc
    if kind == "iterator":
        it = smach.Iterator(
            outcomes=list(OUTCOMES),
            input_keys=[],
            output_keys=[],
            it=range(rng.randint(0, 3)),
            exhausted_outcome="a",
        )
        it.set_contained_state(
            "BODY", random_machine(rng, depth + 1, max_depth), loop_outcomes=["a"]
        )
        return it
    if kind == "retry":
        return smach.Retry.wrap(
            "TRY", random_machine(rng, depth + 1, max_depth), attempts=2, retry_outcomes=["b"]
        )
    return smach.Timeout.wrap(
        "GUARD",
        random_machine(rng, depth + 1, max_depth),
        timeout=rng.choice((0.002, 0.01, 1.0)),
        outcomes=list(OUTCOMES),
        timeout_outcome="b",
    )


@dataclass
class StressReport:
    """What happened over all runs."""

    runs: int = 0
    outcomes: dict[str, int] = field(default_factory=dict)
    errors: int = 0
    preempts_sent: int = 0
    hung: int = 0
    unexpected: list[str] = field(default_factory=list)
    max_seconds: float = 0.0


def stress(
    runs: int, seed: int = 0, *, time_bound: float = 10.0, max_depth: int = 3
) -> StressReport:
    """Run ``runs`` random machines, preempting each at a random moment."""
    rng = random.Random(seed)
    report = StressReport()
    for _ in range(runs):
        root = random_machine(rng, 0, max_depth)
        result: list[Any] = []

        def run(root: State = root, result: list[Any] = result) -> None:
            try:
                result.append(root.execute(UserData()))
            except SmachError as exc:
                result.append(exc)
            except BaseException as exc:  # anything else is a bug
                result.append(exc)

        started = time.monotonic()
        worker = threading.Thread(target=run, name="stress-run", daemon=True)
        worker.start()
        if rng.random() < 0.6:
            time.sleep(rng.choice((0.0, 0.0005, 0.002, 0.01)))
            root.request_preempt()
            report.preempts_sent += 1
        worker.join(time_bound)
        elapsed = time.monotonic() - started
        report.max_seconds = max(report.max_seconds, elapsed)
        report.runs += 1
        if worker.is_alive():
            report.hung += 1
            continue
        value = result[0]
        if isinstance(value, SmachError):
            report.errors += 1
        elif isinstance(value, BaseException):
            report.unexpected.append(f"{type(value).__name__}: {value}")
        elif value in OUTCOMES:
            report.outcomes[value] = report.outcomes.get(value, 0) + 1
        else:
            report.unexpected.append(f"outcome {value!r}")
    return report
