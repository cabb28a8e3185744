"""The viewer's control endpoints: buttons and breakpoints behind a per-run token.

``enable_controls(viewer, controller)`` turns a read-only viewer into a control
panel for one :class:`~smach.control.Controller`:

* ``GET /api/control`` returns the control state (``running``, ``paused``,
  ``at_breakpoint`` ...), the breakpoints and the states they match, the states
  held and running (with their outcomes, for *force outcome*) and the last control
  actions. Reading needs no token (the page is readable anyway).
* ``POST /api/control`` with a JSON body ``{"action": ..., ...}`` performs an action;
  it needs the header ``X-Control-Token`` with the run's token and
  ``Content-Type: application/json``. An extra action's reply holds what it returned
  as text (``result``) and, when that is a mapping or a list (plan_bridge's order
  listing, say), as JSON too (``data``).

Security: the token is random per run (``secrets``), compared in constant time,
and only shown in the URL printed for the operator (``...#token=...``, a fragment,
so it is never sent in a request line or a Referer). A page of another origin can
neither read the token nor send the custom header (no CORS is answered), and the
server's Host check still applies; the server stays on loopback unless told
otherwise. Bodies are bounded (16 KB) and parsed as JSON only.
"""

from __future__ import annotations

import hmac
import json
import secrets
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from smach.container import Container
from smach.control import ControlError, Controller

__all__ = ["MAX_BODY", "ControlledViewer", "ViewerControls", "enable_controls"]

MAX_BODY = 16 * 1024

#: An extra action (e.g. plan_bridge's mission controls): called with the request
#: body; raises ValueError (or a subclass) with a message for the operator.
Action = Callable[[Mapping[str, Any]], object]

_CORE_ACTIONS = (
    "pause",
    "resume",
    "step",
    "preempt",
    "force_outcome",
    "toggle_breakpoint",
    "add_breakpoint",
    "remove_breakpoint",
    "clear_breakpoints",
)


class Headers(Protocol):
    """The request headers (``http.client.HTTPMessage`` or a dict)."""

    def get(self, name: str, /) -> Any: ...


class ViewerControls:
    """What the viewer's control endpoints do (the HTTP side is in the server)."""

    def __init__(
        self,
        controller: Controller,
        *,
        token: str | None = None,
        actions: Mapping[str, Action] | None = None,
    ) -> None:
        self.controller = controller
        self.token = token or secrets.token_urlsafe(24)
        clash = sorted(set(actions or {}) & set(_CORE_ACTIONS))
        if clash:
            raise ValueError(f"extra control actions {clash} would hide the built-in ones")
        self.actions = dict(actions or {})

    def authorised(self, token: str | None) -> bool:
        return token is not None and hmac.compare_digest(token.encode(), self.token.encode())

    def status(self, known_paths: list[str]) -> dict[str, Any]:
        ctl = self.controller
        status = ctl.status()
        data = status.to_json()
        data["matching"] = [p for p in known_paths if ctl.matches(p) is not None]
        outcomes: dict[str, list[str]] = {}
        for path in status.running:
            try:
                state = ctl.find(path)
            except ControlError:
                continue
            if not isinstance(state, Container):
                outcomes[path] = list(state.get_registered_outcomes())
        data["outcomes"] = outcomes
        data["actions"] = [*_CORE_ACTIONS, *sorted(self.actions)]
        data["history"] = [r.to_json() for r in list(ctl.history)[-15:]]
        return data

    def perform(self, body: Mapping[str, Any], *, source: str | None = None) -> dict[str, Any]:
        """Carry out one request; ValueError (-> 400) with a message when it cannot be.

        ``source`` names where it came from (default: the body's ``source`` when it is
        ``viewer`` or ``cli``, else ``viewer``); ROS services pass ``ros``.
        """
        action = body.get("action")
        path = body.get("path")
        if path is not None and not isinstance(path, str):
            raise ValueError(f"'path' must be a string, got {path!r}")
        ctl = self.controller
        if source is None:
            # The page, or `plan-bridge control` (same HTTP API).
            given = body.get("source")
            source = given if isinstance(given, str) and given in ("viewer", "cli") else "viewer"
        body = {**body, "source": source}  # extra actions read it too
        try:
            if action in _CORE_ACTIONS:
                _perform_core(ctl, action, body, path, source)
            elif isinstance(action, str) and action in self.actions:
                return self._perform_extra(action, body)
            else:
                allowed = ", ".join([*_CORE_ACTIONS, *sorted(self.actions)])
                raise ValueError(f"unknown control action {action!r}; actions: {allowed}")
        except ControlError as exc:
            raise ValueError(str(exc)) from exc
        return {"ok": True, "status": ctl.status().to_json()}

    def _perform_extra(self, action: str, body: Mapping[str, Any]) -> dict[str, Any]:
        """Call the extra ``action``: the reply holds what it returned as text
        (``result``) and, when that is a mapping or a list, as JSON data (``data``)."""
        try:
            result = self.actions[action](body)
        except ValueError:
            raise
        except Exception as exc:  # an answer, never a dropped connection
            raise ValueError(f"{action} failed: {type(exc).__name__}: {exc}") from exc
        if isinstance(result, Mapping | list | tuple):
            data = json.loads(json.dumps(result, default=str, ensure_ascii=False))
            return {"ok": True, "result": json.dumps(data, ensure_ascii=False), "data": data}
        return {"ok": True, "result": str(result) if result is not None else None}

    def handle_post(self, headers: Headers, read: Callable[[int], bytes]) -> dict[str, Any]:
        """Check the headers and the body of a POST, then :meth:`perform` it.

        Raises PermissionError (-> 403) for a missing or wrong token and ValueError
        (-> 400) for a bad body.
        """
        if not self.authorised(headers.get("X-Control-Token")):
            raise PermissionError("missing or wrong control token (X-Control-Token)")
        if (headers.get("Content-Type") or "").split(";")[0].strip() != "application/json":
            raise ValueError("control requests are JSON (Content-Type: application/json)")
        try:
            length = int(headers.get("Content-Length") or "0")
        except ValueError:
            raise ValueError("bad Content-Length") from None
        if length <= 0 or length > MAX_BODY:
            raise ValueError(f"a control request body is 1 to {MAX_BODY} bytes")
        try:
            body = json.loads(read(length).decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ValueError(f"the body is not JSON: {exc}") from None
        if not isinstance(body, dict):
            raise ValueError('the body must be a JSON object like {"action": "pause"}')
        return self.perform(body)


def _perform_core(
    ctl: Controller, action: str, body: Mapping[str, Any], path: str | None, source: str
) -> None:
    """Carry out one of the :data:`_CORE_ACTIONS` on ``ctl``."""
    if action == "preempt":
        ctl.preempt(path or None, source=source)
    elif action == "force_outcome":
        outcome = body.get("outcome")
        if not isinstance(outcome, str):
            raise ValueError("force_outcome needs 'outcome' (a string)")
        ctl.force_outcome(outcome, path or None, source=source)
    elif action in ("toggle_breakpoint", "add_breakpoint", "remove_breakpoint"):
        pattern = body.get("pattern", path)
        if not isinstance(pattern, str):
            raise ValueError(f"{action} needs 'pattern' (a state path or a glob)")
        getattr(ctl, action)(pattern, source=source)
    else:  # pause, resume, step, clear_breakpoints: nothing to say but who asks
        getattr(ctl, action)(source=source)


class ControlledViewer(Protocol):
    """What :func:`enable_controls` needs of a viewer (a
    :class:`~smach.introspection.server.ViewerServer`, which imports this module): where
    its control endpoints are, and its address."""

    controls: ViewerControls | None

    @property
    def url(self) -> str: ...


def enable_controls(
    viewer: ControlledViewer,
    controller: Controller,
    *,
    token: str | None = None,
    actions: Mapping[str, Action] | None = None,
) -> str:
    """Give ``viewer`` control buttons for ``controller``; return the URL with the token.

    Open that URL (it carries the token in its fragment) to get a working panel;
    without the token the page shows the control state read-only.
    """
    controls = ViewerControls(controller, token=token, actions=actions)
    viewer.controls = controls
    return f"{viewer.url}#token={controls.token}"
