"""The ``view`` and ``export`` subcommands of ``plan-bridge``.

``plan-bridge view RUN.jsonl [--port N]`` serves the smach viewer page over a
journal written by ``plan-bridge run --journal RUN.jsonl`` (time slider, step
forward/back, the plan panel with replans and decisions); with ``--export FORMAT``
it writes DOT, Mermaid or SVG instead of serving. ``plan-bridge export`` is the
same export as its own command. The work is done by :mod:`smach.introspection.cli`.
"""

from __future__ import annotations

import argparse

from plan_bridge.cli.base import Command

__all__: list[str] = []


def _configure_view(parser: argparse.ArgumentParser) -> None:
    from smach.introspection.cli import add_moment, configure_view

    configure_view(parser)
    parser.add_argument(
        "--export",
        choices=("dot", "mermaid", "svg"),
        metavar="FORMAT",
        help="write the machine as dot, mermaid or svg instead of serving the page",
    )
    add_moment(parser)
    parser.add_argument("-o", "--output", metavar="FILE", help="with --export: write to FILE")
    parser.add_argument(
        "--check",
        action="store_true",
        help="check that the journal tells what happened (every event in the structure in "
        "force, structures written when machines start, replay at every event) and exit",
    )


def _mission_given(path: str) -> str | None:
    """What to say when ``path`` is a mission (folder or PDDL file), not a journal."""
    from pathlib import Path

    if Path(path).is_dir() or path.endswith(".pddl"):
        return (
            f"{path}: a mission, not a journal; view and export replay a journal written by "
            f"'plan-bridge run TARGET --journal RUN.jsonl' (to watch a mission as it runs: "
            f"'plan-bridge run TARGET --viewer')"
        )
    return None


def _view(args: argparse.Namespace) -> int:
    from plan_bridge.cli.base import fail
    from smach.introspection.cli import run_export, run_view

    mission = _mission_given(args.journal)
    if mission is not None:
        return fail(mission)
    if args.check:
        return _check(args.journal)
    if args.export:
        args.format = args.export
        return run_export(args, prog="plan-bridge")
    if args.at is not None or args.event is not None or args.output:
        return fail("--at, --event and --output go with --export")
    return run_view(args, prog="plan-bridge")


def _check(path: str) -> int:
    from plan_bridge.cli.base import EXIT_FAILED, EXIT_OK, fail
    from smach.introspection.fidelity import journal_problems

    try:
        problems = journal_problems(path)
    except (OSError, ValueError) as exc:
        return fail(f"{path}: cannot read the journal: {exc}")
    for problem in problems:
        print(f"{path}: {problem}")
    if problems:
        return EXIT_FAILED
    print(f"{path}: OK (every event in the structure in force; replay exact at every event)")
    return EXIT_OK


def _configure_export(parser: argparse.ArgumentParser) -> None:
    from smach.introspection.cli import configure_export

    configure_export(parser)


def _export(args: argparse.Namespace) -> int:
    from plan_bridge.cli.base import fail
    from smach.introspection.cli import run_export

    mission = _mission_given(args.journal)
    if mission is not None:
        return fail(mission)
    return run_export(args, prog="plan-bridge")


COMMANDS = (
    Command(
        "view",
        "replay a run's journal in the browser viewer (or export it with --export)",
        _configure_view,
        _view,
        description="Serve the viewer page over RUN.jsonl (written by plan-bridge run --journal) "
        "on 127.0.0.1, with a time slider, step forward/back and the plan panel.",
    ),
    Command(
        "export",
        "write DOT, Mermaid or SVG of a journal's machine at a given moment",
        _configure_export,
        _export,
    ),
)
