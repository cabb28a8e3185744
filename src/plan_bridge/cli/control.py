"""The ``control`` subcommand: operate a running mission from another terminal.

``plan-bridge run ... --control`` prints a control URL (the viewer's address with a
per-run token in its fragment). Give it to ``plan-bridge control``::

    plan-bridge control URL status
    plan-bridge control URL pause | resume | step
    plan-bridge control URL break '*/PICK'        # toggle a breakpoint (path or glob)
    plan-bridge control URL force succeeded [--path /ROOT/PLAN/03_PICK/SKILL]
    plan-bridge control URL preempt [--path PATH]
    plan-bridge control URL skip [--no-effects] [--step LABEL]
    plan-bridge control URL replan
    plan-bridge control URL goal '(at robot1 kitchen)'
    plan-bridge control URL abort [REASON]

Each action goes to the same control model as the viewer's buttons and is journaled
with the source ``cli``. Exit codes: 0 done, 1 refused by the mission (the reason is
printed), 2 bad input or no such run.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from plan_bridge.cli.base import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, Command, fail

__all__: list[str] = []

ACTIONS = (
    "status",
    "pause",
    "resume",
    "step",
    "break",
    "force",
    "preempt",
    "skip",
    "replan",
    "goal",
    "abort",
)
_NEEDS_ARGUMENT = {"break": "PATTERN", "force": "OUTCOME", "goal": "ATOMS"}


def _configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="URL", help="the control URL printed by run --control")
    parser.add_argument("action", choices=ACTIONS, metavar="ACTION", help=", ".join(ACTIONS))
    parser.add_argument(
        "argument",
        nargs="?",
        help="break: a state path or glob; force: an outcome; goal: atoms; abort: a reason",
    )
    parser.add_argument("--path", help="force/preempt: the state (default: the active leaf/root)")
    parser.add_argument("--step", help="skip: the running step's label or index")
    parser.add_argument("--no-effects", action="store_true", help="skip: leave the belief as it is")
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the run (default 10)"
    )
    parser.add_argument("--json", action="store_true", help="print the reply as JSON")


def _body(args: argparse.Namespace) -> dict[str, Any]:
    action = args.action
    needed = _NEEDS_ARGUMENT.get(action)
    if needed and not args.argument:
        raise ValueError(f"{action} needs {needed}")
    body: dict[str, Any] = {"source": "cli"}
    if action == "break":
        body.update(action="toggle_breakpoint", pattern=args.argument)
    elif action == "force":
        body.update(action="force_outcome", outcome=args.argument)
        if args.path:
            body["path"] = args.path
    elif action == "preempt":
        body["action"] = "preempt"
        if args.path:
            body["path"] = args.path
    elif action == "skip":
        body.update(action="skip", apply_effects=not args.no_effects)
        if args.step:
            body["step"] = args.step
    elif action == "goal":
        body.update(action="goal", goal=args.argument)
    elif action == "abort":
        body.update(action="abort", reason=args.argument or "")
    else:
        body["action"] = action
    return body


def _split(url: str) -> tuple[str, str, int, str]:
    """``http://127.0.0.1:PORT/#token=T`` -> (scheme-less host, host, port, token)."""
    from urllib.parse import urlsplit

    parts = urlsplit(url)
    token = ""
    for item in parts.fragment.split("&"):
        if item.startswith("token="):
            token = item[len("token=") :]
    if parts.scheme != "http" or not parts.hostname or parts.port is None:
        raise ValueError(f"expected the control URL printed by run --control, got {url!r}")
    if not token:
        raise ValueError(f"{url!r} has no #token=...; use the URL printed by run --control")
    return parts.netloc, parts.hostname, parts.port, token


def _control(args: argparse.Namespace) -> int:
    import http.client

    try:
        netloc, host, port, token = _split(args.url)
        body = None if args.action == "status" else _body(args)
    except ValueError as exc:
        return fail(str(exc))
    connection = http.client.HTTPConnection(host, port, timeout=args.timeout)
    try:
        if body is None:
            connection.request("GET", "/api/control", headers={"Host": netloc})
        else:
            data = json.dumps(body).encode("utf-8")
            connection.request(
                "POST",
                "/api/control",
                body=data,
                headers={
                    "Host": netloc,
                    "Content-Type": "application/json",
                    "X-Control-Token": token,
                },
            )
        response = connection.getresponse()
        status = response.status
        reply = json.loads(response.read().decode("utf-8") or "{}")
    except (OSError, ValueError) as exc:
        return fail(f"no run answers at {host}:{port} ({exc})")
    finally:
        connection.close()
    if args.json:
        print(json.dumps(reply))
    if status == 200 and body is None:
        if not reply.get("enabled"):
            return fail("that run has no control endpoints (start it with --control)")
        if not args.json:
            print(f"control: {reply['describe']}")
            if reply.get("breakpoints"):
                print("breakpoints: " + " ".join(reply["breakpoints"]))
            if reply.get("running"):
                print("running: " + " ".join(reply["running"]))
        return EXIT_OK
    if status == 200:
        if not args.json:
            status_now = reply.get("status") or {}
            done = reply.get("result") or status_now.get("describe") or "ok"
            print(f"{args.action}: {done}")
        return EXIT_OK
    message = reply.get("error", f"HTTP {status}")
    if status == 400:  # the run refused the request: say why
        print(f"plan-bridge: refused: {message}", file=sys.stderr)
        return EXIT_FAILED
    return fail(message, EXIT_BAD_INPUT)


COMMANDS = (
    Command(
        "control",
        "pause, step, breakpoints, force outcome, skip, replan, new goal or abort a running mission",
        _configure,
        _control,
        description=__doc__.split("\n\n")[0] if __doc__ else "",
    ),
)
