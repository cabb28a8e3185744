"""Cost of the runtime-control hook on the transition path when no control is in use.

Usage::

    .venv/bin/python benchmarks/control_bench.py                  # about 30 s
    .venv/bin/python benchmarks/control_bench.py --quick          # a few seconds
    .venv/bin/python benchmarks/control_bench.py --before REV     # compare with REV

The hook is in ``Container.step_child``, which a step reaches only when somebody
watches it (a controller subscribes to the tree, so a controlled tree is watched). On
an unwatched step, what remains of it is the test
``if watched or log_steps or sm._preempt_requested`` in
``StateMachine.run_children`` (smach/state_machine.py) that decides whether a step
goes through ``step_child``. To measure that, the working tree's ``StateMachine`` is
loaded twice into this process: as it is, and with that test replaced by ``False``
(which Python compiles away, leaving a machine that can never be watched: an upper
bound on what the hook costs an unwatched step); ``--before REV`` loads the file of a
commit instead.
The same 1000-state chain of trivial states (the ``chain`` scenario of
core_bench.py) is built with each. Trials alternate between the two
(round-robin, gc disabled while timing) so that drift of a shared machine hits
both alike; the table gives the median us/transition of each and their ratio. A
third column runs the current machine with a controller attached and running (no
pause, no breakpoint), for information: that is the cost of control in use.
"""

from __future__ import annotations

import argparse
import gc
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import smach
from smach.control import Controller

ROOT = Path(__file__).resolve().parents[1]
HOOK_TEST = "watched or log_steps or sm._preempt_requested"


class Trivial(smach.State):
    def __init__(self) -> None:
        super().__init__(outcomes=["done"])

    def execute(self, ud: Any) -> str:
        return "done"


def load_state_machine(rev: str | None, *, strip: bool = False) -> type[smach.StateMachine]:
    """``StateMachine`` at ``rev`` (None: the working tree's), loaded anew.

    ``strip`` replaces the hook's test by ``False``. Both sides are loaded the same
    way (a fresh module from a temporary file), so neither gets an advantage from
    where its code objects live.
    """
    if rev is None:
        text = (ROOT / "src" / "smach" / "state_machine.py").read_text(encoding="utf-8")
        if strip:
            if HOOK_TEST not in text:
                raise SystemExit(f"the hook's test {HOOK_TEST!r} is not in state_machine.py")
            text = text.replace(HOOK_TEST, "False")
    else:
        text = subprocess.run(
            ["git", "show", f"{rev}:src/smach/state_machine.py"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as handle:
        handle.write(text)
    spec = importlib.util.spec_from_file_location("smach_state_machine_before", handle.name)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    Path(handle.name).unlink()
    cls: type[smach.StateMachine] = module.StateMachine
    return cls


def chain(cls: type[smach.StateMachine], n: int) -> smach.StateMachine:
    sm = cls(outcomes=["end"])
    for i in range(n):
        sm.add(f"S{i}", Trivial(), transitions={"done": f"S{i + 1}" if i + 1 < n else "end"})
    sm.execute()  # compile once
    return sm


def trial(sm: smach.StateMachine, n: int, min_s: float) -> float:
    """us per transition over enough runs to last ``min_s``."""
    runs = 0
    gc.disable()
    try:
        started = time.perf_counter()
        while True:
            sm.execute()
            runs += 1
            elapsed = time.perf_counter() - started
            if elapsed >= min_s:
                break
    finally:
        gc.enable()
    return elapsed / (runs * n) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer, shorter trials")
    parser.add_argument(
        "--before", default=None, help="a commit to compare with (default: the hook compiled out)"
    )
    parser.add_argument("--states", type=int, default=1000)
    args = parser.parse_args()
    trials, min_s = (7, 0.05) if args.quick else (31, 0.2)
    n = args.states
    before = chain(load_state_machine(args.before, strip=args.before is None), n)
    # The same code as `before`, loaded again: the spread between the two is the noise.
    twin = chain(load_state_machine(args.before, strip=args.before is None), n)
    now = chain(load_state_machine(None), n)
    controlled = chain(load_state_machine(None), n)
    ctl = Controller(controlled)
    machines = {"before": before, "twin": twin, "now": now, "controlled": controlled}
    samples: dict[str, list[float]] = {name: [] for name in machines}
    order = list(machines)
    for t in range(trials):
        for name in order[t % 4 :] + order[: t % 4]:  # rotate who goes first
            samples[name].append(trial(machines[name], n, min_s))
    ctl.close()
    med = {name: statistics.median(values) for name, values in samples.items()}
    ratios = [b / a for a, b in zip(samples["before"], samples["now"], strict=True)]
    noise = [b / a for a, b in zip(samples["before"], samples["twin"], strict=True)]
    print(f"chain of {n} trivial states, {trials} interleaved trials of >= {min_s} s each")
    what = args.before or "the working tree with the hook's test compiled out"
    print(f"python {sys.version.split()[0]}, before = {what}")
    print(f"{'machine':<34}{'us/transition (median)':>24}")
    print(f"{'before the hook':<34}{med['before']:>24.4f}")
    print(f"{'before the hook, loaded again':<34}{med['twin']:>24.4f}")
    print(f"{'with the hook, no control':<34}{med['now']:>24.4f}")
    print(f"{'with a controller attached':<34}{med['controlled']:>24.4f}")
    ratio = statistics.median(ratios)
    print(
        f"hook cost, no control: {100 * (med['now'] / med['before'] - 1):+.1f}% (ratio of medians)"
    )
    print(f"hook cost, no control: {100 * (ratio - 1):+.1f}% (median of per-trial ratios)")
    spread = statistics.median(noise)
    print(f"noise (same code twice): {100 * (spread - 1):+.1f}% (median of per-trial ratios)")
    print(
        f"control in use (attached, running): {100 * (med['controlled'] / med['before'] - 1):+.1f}%"
    )


if __name__ == "__main__":
    main()
