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
    plan-bridge control URL order GOAL [--id ID] [--priority N] [--within S]
    plan-bridge control URL cancel ID [REASON]
    plan-bridge control URL orders [--json]       # every order and its status

Each action goes to the same control model as the viewer's buttons and is journaled
with the source ``cli``. ``order``, ``cancel`` and ``orders`` go to a mission of orders
(``run --orders-open``, or ``--orders`` for cancel and orders; docs/orders.md). Exit
codes: 0 done, 1 refused by the mission (the reason is printed), 2 bad input or no
such run.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping, Sequence
from typing import Any

from plan_bridge.cli.base import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_OK,
    Command,
    fail,
    positive_seconds,
)

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
    "order",
    "cancel",
    "orders",
)
_NEEDS_ARGUMENT = {
    "break": "PATTERN",
    "force": "OUTCOME",
    "goal": "ATOMS",
    "order": "GOAL (atoms or a goal's name)",
    "cancel": "the ID of an order",
}
#: The actions of a mission of orders (plan_bridge.orders.requests.OrderDesk).
ORDER_ACTIONS = ("order", "cancel", "orders")
#: What a mission that runs one goal answers to them.
ONE_GOAL = "this mission runs one goal; start it with --orders or --orders-open"


def _configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="URL", help="the control URL printed by run --control")
    parser.add_argument("action", choices=ACTIONS, metavar="ACTION", help=", ".join(ACTIONS))
    parser.add_argument(
        "argument",
        nargs="?",
        help="break: a state path or glob; force: an outcome; goal: atoms; abort: a reason; "
        "order: the goal (atoms or a goal's name); cancel: the order's id",
    )
    parser.add_argument(
        "reason", nargs="*", metavar="REASON", help="cancel: why (the rest of the line)"
    )
    parser.add_argument("--path", help="force/preempt: the state (default: the active leaf/root)")
    parser.add_argument("--step", help="skip: the running step's label or index")
    parser.add_argument("--no-effects", action="store_true", help="skip: leave the belief as it is")
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the run (default 10)"
    )
    parser.add_argument("--id", help="order: the order's id (default: o1, o2, ...)")
    parser.add_argument("--priority", type=int, help="order: higher first (an integer, default 0)")
    parser.add_argument(
        "--within",
        type=positive_seconds,
        metavar="S",
        help="order: due S seconds (the mission's clock) after it arrives",
    )
    parser.add_argument(
        "--json", action="store_true", help="print the reply as JSON (orders: the list of orders)"
    )


def _body(args: argparse.Namespace) -> dict[str, Any]:
    action = args.action
    needed = _NEEDS_ARGUMENT.get(action)
    if needed and not (args.argument or "").strip():
        raise ValueError(f"{action} needs {needed}")
    if args.reason and action != "cancel":
        raise ValueError(
            f"{action} takes one argument; quote it, e.g. "
            f"'{' '.join([args.argument or '', *args.reason]).strip()}'"
        )
    given = [f"--{o}" for o in ("id", "priority", "within") if getattr(args, o) is not None]
    if given and action != "order":
        verb = "goes" if len(given) == 1 else "go"
        raise ValueError(f"{' and '.join(given)} {verb} with order only, not {action}")
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
    elif action == "order":
        body.update(_order_body(args))
    elif action == "cancel":
        body.update(action="cancel", id=args.argument.strip(), reason=" ".join(args.reason))
    else:
        body["action"] = action
    return body


def _order_body(args: argparse.Namespace) -> dict[str, Any]:
    """The request of ``order GOAL [--id ID] [--priority N] [--within S]``."""
    body: dict[str, Any] = {"action": "order", "goal": args.argument}
    if args.id is not None:
        if not args.id.strip():
            raise ValueError("--id needs a name, e.g. --id soda-7")
        body["id"] = args.id
    if args.priority is not None:
        body["priority"] = args.priority
    if args.within is not None:
        body["within"] = args.within
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
    try:
        netloc, host, port, token = _split(args.url)
        body = None if args.action == "status" else _body(args)
    except ValueError as exc:
        return fail(str(exc))
    try:
        if args.action in ORDER_ACTIONS:
            # Only a mission of orders has them: say so rather than "unknown action".
            status, state = _request(args, netloc, host, port, token, None)
            if status == 200 and state.get("enabled") and "order" not in state.get("actions", ()):
                print(f"plan-bridge: refused: {ONE_GOAL}", file=sys.stderr)
                return EXIT_FAILED
        status, reply = _request(args, netloc, host, port, token, body)
    except (OSError, ValueError) as exc:
        return fail(f"no run answers at {host}:{port} ({exc})")
    if args.json and not (status == 200 and args.action == "orders"):
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
        _print_done(args, reply)
        return EXIT_OK
    message = reply.get("error", f"HTTP {status}")
    if status == 400:  # the run refused the request: say why
        print(f"plan-bridge: refused: {message}", file=sys.stderr)
        return EXIT_FAILED
    return fail(message, EXIT_BAD_INPUT)


def _request(
    args: argparse.Namespace,
    netloc: str,
    host: str,
    port: int,
    token: str,
    body: dict[str, Any] | None,
) -> tuple[int, dict[str, Any]]:
    """GET (``body`` None) or POST ``/api/control``: the HTTP status and the JSON reply.
    Raises OSError (no run answers) or ValueError (the reply is not JSON)."""
    import http.client

    connection = http.client.HTTPConnection(host, port, timeout=args.timeout)
    try:
        if body is None:
            connection.request("GET", "/api/control", headers={"Host": netloc})
        else:
            connection.request(
                "POST",
                "/api/control",
                body=json.dumps(body).encode("utf-8"),
                headers={
                    "Host": netloc,
                    "Content-Type": "application/json",
                    "X-Control-Token": token,
                },
            )
        response = connection.getresponse()
        reply = json.loads(response.read().decode("utf-8") or "{}")
    finally:
        connection.close()
    if not isinstance(reply, dict):
        raise ValueError(f"expected a JSON object, got {type(reply).__name__}")
    return response.status, reply


def _print_done(args: argparse.Namespace, reply: Mapping[str, Any]) -> None:
    """What a carried-out action did (``--json``: its data for ``orders``)."""
    data = reply.get("data")
    if args.action == "orders":
        orders = data if isinstance(data, list) else []
        print(json.dumps(orders) if args.json else orders_table(orders))
        return
    if args.json:
        return
    if args.action == "order" and isinstance(data, Mapping):
        print(
            f"order {data.get('id')}: {data.get('goal')} (taken when the mission next looks; "
            f"plan-bridge control URL orders shows its status)"
        )
    elif args.action == "cancel" and isinstance(data, Mapping):
        print(f"cancel: order {data.get('id')} {data.get('status')}: {data.get('reason', '')}")
    else:
        status_now = reply.get("status") or {}
        done = reply.get("result") or status_now.get("describe") or "ok"
        print(f"{args.action}: {done}")


def orders_table(orders: Sequence[Mapping[str, Any]]) -> str:
    """Orders (``OrderState.to_json()``) as a table: id, status, robots, arrived, ended,
    latency and reason (times: seconds of the mission's clock)."""
    if not orders:
        return "no orders yet"
    head = ("ID", "STATUS", "ROBOTS", "ARRIVED", "ENDED", "LATENCY", "REASON")
    rows = [head]
    counts: dict[str, int] = {}
    for order in orders:
        status = str(order.get("status", ""))
        counts[status] = counts.get(status, 0) + 1
        latency = _seconds(order.get("latency"))
        if latency != "-":
            latency += " s" + (" (late)" if order.get("late") else "")
        rows.append(
            (
                str(order.get("id", "")),
                status,
                ",".join(str(r) for r in order.get("robots", ())) or "-",
                _seconds(order.get("arrived")),
                _seconds(order.get("ended")),
                latency,
                str(order.get("reason", "")),
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(head) - 1)]
    lines = [
        "  ".join(
            [*(cell.ljust(w) for cell, w in zip(row, widths, strict=False)), row[-1]]
        ).rstrip()
        for row in rows
    ]
    tally = ", ".join(f"{n} {status}" for status, n in counts.items())
    lines.append(f"{len(orders)} order{'s' if len(orders) != 1 else ''}: {tally}")
    return "\n".join(lines)


def _seconds(value: object) -> str:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return f"{value:.1f}"
    return "-"


COMMANDS = (
    Command(
        "control",
        "pause, step, breakpoints, force outcome, skip, replan, new goal, abort or send "
        "orders to a running mission",
        _configure,
        _control,
        description=__doc__.split("\n\n")[0] if __doc__ else "",
    ),
)
