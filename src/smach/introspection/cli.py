"""``python -m smach.introspection``: view, replay and export journals.

::

    python -m smach.introspection view RUN.jsonl [--port N] [--host H] [--follow]
    python -m smach.introspection export RUN.jsonl --format dot|mermaid|svg
                                         [--at SECONDS | --event N] [-o FILE]
    python -m smach.introspection ros SERVER_NAME [--port N] [--host H] [--timeout S]

``ros`` follows a remote executive through its IntrospectionServer topics (needs
the ``ros`` extra; :class:`smach.ros.viewer_source.RosSource`).

``plan-bridge view`` and ``plan-bridge export`` reuse :func:`configure_view`,
:func:`configure_export`, :func:`run_view` and :func:`run_export`.
Exit codes: 0 success, 2 bad input (one line on stderr, no traceback).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from smach.introspection.source import Source

__all__ = [
    "add_moment",
    "build_parser",
    "configure_export",
    "configure_ros",
    "configure_view",
    "main",
    "run_export",
    "run_ros",
    "run_view",
]

EXIT_OK = 0
EXIT_BAD_INPUT = 2

_N = TypeVar("_N", int, float)


def _number(
    text: str, convert: Callable[[str], _N], kind: str, fits: Callable[[_N], bool], bounds: str
) -> _N:
    """``text`` read by ``convert``: an argparse error names ``kind`` or the ``bounds``."""
    try:
        value = convert(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {kind}, got {text!r}") from None
    if not fits(value):
        raise argparse.ArgumentTypeError(f"expected {bounds}, got {text!r}")
    return value


def _port(text: str) -> int:
    return _number(text, int, "a port number", lambda v: 0 <= v <= 65535, "a port number 0..65535")


def _seconds(text: str) -> float:
    return _number(
        text,
        float,
        "seconds (a number)",
        lambda v: 0 <= v < float("inf"),
        "a number of seconds >= 0",
    )


def _count(text: str) -> int:
    return _number(text, int, "a whole number", lambda v: v >= 0, "a number >= 0")


def add_moment(parser: argparse.ArgumentParser) -> None:
    moment = parser.add_mutually_exclusive_group()
    moment.add_argument(
        "--at", type=_seconds, metavar="SECONDS", help="the moment SECONDS after the first event"
    )
    moment.add_argument(
        "--event", type=_count, metavar="N", help="the moment after the first N events"
    )


def configure_export(parser: argparse.ArgumentParser, *, format_required: bool = True) -> None:
    """Arguments of ``export`` (journal, --format, --at/--event, -o)."""
    parser.add_argument("journal", metavar="RUN.jsonl", help="a journal (JSON lines)")
    parser.add_argument(
        "--format",
        choices=("dot", "mermaid", "svg"),
        required=format_required,
        help="dot (Graphviz), mermaid (stateDiagram-v2) or svg (no Graphviz needed)",
    )
    add_moment(parser)
    parser.add_argument("-o", "--output", metavar="FILE", help="write to FILE (default: stdout)")


def _add_listen(parser: argparse.ArgumentParser) -> None:
    """--port and --host of the page's server."""
    parser.add_argument(
        "--port", type=_port, default=0, help="port to listen on (default: a free one)"
    )
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default 127.0.0.1; anything else exposes the page to the network)",
    )


def configure_view(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``view`` (journal, --port, --host, --follow)."""
    parser.add_argument("journal", metavar="RUN.jsonl", help="a journal (JSON lines)")
    _add_listen(parser)
    parser.add_argument(
        "--follow", action="store_true", help="keep reading lines appended to the journal"
    )


def configure_ros(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``ros`` (server name, --port, --host, --timeout)."""
    parser.add_argument(
        "server", metavar="SERVER_NAME", help="the name given to IntrospectionServer"
    )
    _add_listen(parser)
    parser.add_argument(
        "--timeout",
        type=_seconds,
        default=10.0,
        help="seconds to wait for the server's first message (default 10)",
    )


def _fail(prog: str, message: str) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr, flush=True)
    return EXIT_BAD_INPUT


def run_export(args: argparse.Namespace, prog: str = "smach-viewer") -> int:
    from smach.introspection.export import export_journal

    try:
        text = export_journal(args.journal, args.format, at=args.at, event=args.event)
    except (OSError, ValueError) as exc:
        return _fail(prog, f"{args.journal}: {getattr(exc, 'strerror', None) or exc}")
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as exc:
            return _fail(prog, f"{args.output}: {exc.strerror or exc}")
        print(f"{prog}: wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _serve(source: Source, args: argparse.Namespace, prog: str, doing: str) -> int:
    """Serve the page over ``source`` at ``--host``/``--port`` until Ctrl-C."""
    from smach.introspection.server import serve

    try:
        viewer = serve(source, port=args.port, host=args.host, quiet=True)
    except OSError as exc:
        source.close()
        return _fail(prog, f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}")
    try:
        print(f"{prog}: {doing} at {viewer.url} (Ctrl-C to stop)", file=sys.stderr)
        sys.stderr.flush()
        viewer.wait()
    except KeyboardInterrupt:  # Ctrl-C as soon as the address is out, before wait()
        viewer.close()
    return EXIT_OK


def run_view(args: argparse.Namespace, prog: str = "smach-viewer") -> int:
    from smach.introspection.source import JournalSource

    try:
        source = JournalSource(args.journal, follow=args.follow)
    except (OSError, ValueError) as exc:
        return _fail(prog, f"{args.journal}: {getattr(exc, 'strerror', None) or exc}")
    return _serve(source, args, prog, f"replaying {args.journal}")


def run_ros(args: argparse.Namespace, prog: str = "smach-viewer") -> int:
    try:
        from smach.ros.viewer_source import RosSource
    except ImportError as exc:
        return _fail(prog, f"the ros command needs rclpy: {exc}")
    from smach.exceptions import SmachError

    try:
        source = RosSource(args.server, timeout=args.timeout)
    except (TimeoutError, ValueError, SmachError) as exc:
        return _fail(prog, str(exc))
    return _serve(source, args, prog, f"following {source.base}")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m smach.introspection",
        description="Replay and export smach journals (JSON lines written by "
        "smach.introspection.journal.Journal), or follow a ROS 2 IntrospectionServer.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    configure_view(sub.add_parser("view", help="serve the viewer page over a journal (replay)"))
    configure_export(
        sub.add_parser(
            "export", help="write DOT, Mermaid or SVG of a journal's machine at a given moment"
        )
    )
    configure_ros(
        sub.add_parser(
            "ros", help="serve the viewer page over a ROS 2 IntrospectionServer (ros extra)"
        )
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "view":
        return run_view(args)
    if args.command == "ros":
        return run_ros(args)
    return run_export(args)
