"""Do `plan-bridge check`, `plan` and `run` agree on every file of the front end's corpus?

    .venv/bin/python tools/front_end_agreement.py [CORPUS] [--jobs N]

Runs the installed console script (``.venv/bin/plan-bridge``, each command in its own
process, as a user would) with ``check``, ``plan`` and ``run`` on every corpus case
(``tests/plan_bridge/pddl/corpus``, each file paired as the corpus test pairs it) and
compares, per case: the exit code, the ``plan-bridge: error:`` paragraph, and the
warnings. Expected: a broken case exits 2 with the same message from all three
commands, naming the case's file and line; an odd-but-valid case exits 0 from all
three (an ``unless-installed`` case may instead be refused by all three alike).
Prints one line per disagreement and a summary; exits 1 when any case disagrees.
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "plan_bridge" / "pddl"))
from corpus_cases import CORPUS, expectations, pair  # noqa: E402

CLI = ROOT / ".venv" / "bin" / "plan-bridge"
COMMANDS = ("check", "plan", "run")


@dataclass(frozen=True)
class Outcome:
    code: int
    error: str  # the "plan-bridge: error: ..." paragraph, "" when none
    warnings: tuple[str, ...]
    traceback: bool


def run_command(command: str, domain: Path, problem: Path) -> Outcome:
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["ROS_DOMAIN_ID"] = str(random.randint(101, 200))
    extra = ["--timeout", "30"] if command in ("plan", "run") else []
    try:
        done = subprocess.run(
            [str(CLI), command, str(domain), str(problem), *extra],
            capture_output=True,
            text=True,
            errors="replace",
            timeout=120,
            env=env,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return Outcome(-1, "hang: no answer after 120 s", (), False)
    # The error paragraph is the last thing a command prints: from its first line on.
    rows = done.stderr.splitlines()
    start = next(
        (
            i
            for i, row in enumerate(rows)
            if row.startswith(("plan-bridge: error: ", "plan-bridge: internal"))
        ),
        len(rows),
    )
    error_rows = rows[start:]
    warnings = [row for row in rows[:start] if row.startswith("warning: ")]
    return Outcome(
        done.returncode,
        "\n".join(error_rows),
        tuple(warnings),
        "Traceback" in done.stderr,
    )


def judge(corpus: Path, path: Path) -> list[str]:
    meta = expectations(path)
    domain, problem = pair(path, meta)
    outcomes = {command: run_command(command, domain, problem) for command in COMMANDS}
    problems: list[str] = []
    codes = {command: outcome.code for command, outcome in outcomes.items()}
    for command, outcome in outcomes.items():
        if outcome.traceback:
            problems.append(f"{command}: traceback")
        if outcome.code == 3:
            problems.append(f"{command}: internal error: {outcome.error}")
    conditional = bool(meta.get("unless-installed"))
    if meta.get("verdict") == "error":
        if set(codes.values()) != {2} and not conditional:
            problems.append(f"exit codes {codes}, expected 2 from each")
        errors = {outcome.error for outcome in outcomes.values()}
        if len(errors) > 1:
            shown = "; ".join(f"{c}: {o.error.splitlines()[:1]}" for c, o in outcomes.items())
            problems.append(f"different messages: {shown}")
        first = outcomes["check"].error
        if codes["check"] == 2:
            where = domain if meta.get("where") == "domain" else problem
            line = meta.get("line", "none")
            location = f"{where}:{line}:" if line != "none" else f"{where}:"
            if location not in first:
                problems.append(f"message does not name {location}: {first.splitlines()[:1]}")
            if meta.get("message", "") not in first:
                problems.append(f"message lacks {meta.get('message')!r}")
    else:
        if conditional and set(codes.values()) == {2}:
            if len({outcome.error for outcome in outcomes.values()}) > 1:
                problems.append("refused with different messages")
        elif set(codes.values()) != {0}:
            shown = "; ".join(
                f"{c}: {o.error.splitlines()[:1]}" for c, o in outcomes.items() if o.code
            )
            problems.append(f"exit codes {codes}, expected 0 from each ({shown})")
        warnings = {outcome.warnings for outcome in outcomes.values()}
        if len(warnings) > 1:
            problems.append(f"different warnings: {warnings}")
    return [f"{path.name}: {p}" for p in problems]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("corpus", nargs="?", default=CORPUS)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    corpus = Path(args.corpus)
    cases = sorted(corpus.glob("*.pddl"))
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        verdicts = list(pool.map(lambda case: judge(corpus, case), cases))
    disagreements = [row for rows in verdicts for row in rows]
    for row in disagreements:
        print(row)
    bad = sum(1 for rows in verdicts if rows)
    print(f"{len(cases)} cases x {len(COMMANDS)} commands: {len(cases) - bad} agree, {bad} do not")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
