"""The browser viewer: a small local HTTP server (standard library only).

:func:`serve` starts it in background threads and returns a :class:`ViewerServer`::

    with smach.introspection.serve(sm) as viewer:   # prints http://127.0.0.1:PORT/
        sm.execute()

Threads: the executing threads only append events to the source's bounded deque.
One *pump* thread polls the source, folds the records into a :class:`History` and
wakes the clients; it limits itself to a small share of the CPU (it sleeps at least
19 times as long as it worked), so a viewer that falls behind skips events (and
resyncs) instead of slowing the machine. Each browser connection has its own thread
(``ThreadingHTTPServer``); a live page gets at most ten coalesced updates a second
over server-sent events: the newest view plus the new timeline records.

Security: binds 127.0.0.1 unless told otherwise, answers only GET, checks the Host
header (so a web page elsewhere cannot reach it by DNS rebinding), sends no CORS
headers, and is read-only unless control endpoints are enabled (see
:mod:`smach.introspection.control_api`: POST behind a per-run token).
"""

from __future__ import annotations

import json
import sys
import threading
import time
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any
from urllib.parse import parse_qs, urlsplit

from smach.introspection.control_api import ViewerControls
from smach.introspection.model import History, ViewModel
from smach.introspection.source import LiveSource, Source
from smach.introspection.structure import StateNode
from smach.state import State

__all__ = ["ViewerServer", "serve"]

STATIC = {
    "app.js": "text/javascript; charset=utf-8",
    "app.css": "text/css; charset=utf-8",
    "graph.css": "text/css; charset=utf-8",
    "control.js": "text/javascript; charset=utf-8",
    "gantt.js": "text/javascript; charset=utf-8",
    "gantt.css": "text/css; charset=utf-8",
    "scene.js": "text/javascript; charset=utf-8",
    "scene.css": "text/css; charset=utf-8",
    "orders.js": "text/javascript; charset=utf-8",
    "orders.css": "text/css; charset=utf-8",
}
MAX_RECORDS_PER_MESSAGE = 300
MAX_RECORDS_PER_REQUEST = 2000
LOOPBACK = {"127.0.0.1", "localhost", "::1", "[::1]"}


def _static(name: str) -> bytes:
    return (resources.files("smach.introspection") / "static" / name).read_bytes()


class ViewerServer:
    """A running viewer; ``close()`` (or leave the ``with`` block) to stop it."""

    def __init__(
        self,
        source: Source,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        title: str | None = None,
        interval: float = 0.1,
        history: int = 50_000,
        max_updates_per_s: float = 10.0,
    ) -> None:
        self.source = source
        self.title = title or str(getattr(source, "title", "smach viewer"))
        self.interval = interval
        self.min_gap = 1.0 / max_updates_per_s
        self.history = History(source.header(), limit=history)
        self._cond = threading.Condition()
        self.version = 0
        self._closing = False
        self._view_cache: tuple[int, str] | None = None
        self.pump_busy_s = 0.0
        self.clients = 0
        #: Control endpoints (smach.introspection.control_api.enable_controls); None: read-only.
        self.controls: ViewerControls | None = None
        self._httpd = ThreadingHTTPServer((host, port), _handler_class(self))
        self._httpd.daemon_threads = True
        self.host = host
        self.port = int(self._httpd.server_address[1])
        self._pump_stop = threading.Event()
        self._pump_lock = threading.Lock()  # the pump thread and catch_up() take turns
        self._pump()  # the journal's records are there before the first request
        self._threads = [
            threading.Thread(
                target=self._httpd.serve_forever, name="smach-viewer-http", daemon=True
            ),
            threading.Thread(target=self._pump_loop, name="smach-viewer-pump", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    # -- pump ------------------------------------------------------------------------------
    def catch_up(self) -> int:
        """Fold what the source has now, without waiting for the pump's next turn (so
        that a page asked right after a run ended shows its end). Returns how many
        records were folded."""
        return self._pump()

    def _pump(self) -> int:
        with self._pump_lock:
            return self._fold(self.source.poll())

    def _fold(self, records: list[dict[str, Any]]) -> int:
        if records:
            with self._cond:
                for record in records:
                    self.history.add(record)
                self.version += 1
                self._cond.notify_all()
        return len(records)

    def _pump_loop(self) -> None:
        while not self._pump_stop.is_set():
            started = time.perf_counter()
            try:
                self._pump()
            except Exception as exc:  # a broken source must not kill the page
                sys.stderr.write(f"smach viewer: source failed: {exc!r}\n")
                self._pump_stop.wait(1.0)
            busy = time.perf_counter() - started
            self.pump_busy_s += busy
            self._pump_stop.wait(max(self.interval, busy * 19))

    # -- data for the handlers -----------------------------------------------------------------
    def info(self) -> dict[str, Any]:
        header = {k: v for k, v in self.history.header.items() if k not in ("structure", "kind")}
        return {
            "title": self.title,
            "live": bool(self.source.live),
            "total": self.history.total,
            "first": self.history.first,
            "controls": self.controls is not None,
            "header": header,
        }

    def view_json(self, at: int | None = None) -> str:
        with self._cond:
            if at is None or at >= self.history.total:
                cached = self._view_cache
                if cached is not None and cached[0] == self.version:
                    return cached[1]
                text = self._dump_view(self.history.model)
                self._view_cache = (self.version, text)
                return text
            return self._dump_view(self.history.view_at(at))

    def gantt_json(self, at: int | None = None) -> str:
        """The Gantt rows of the view after ``at`` records (the newest by default)."""
        with self._cond:
            model = self.history.model if at is None or at >= self.history.total else None
            rows = (model or self.history.view_at(at or 0)).gantt_json()
        return json.dumps(rows, default=str, ensure_ascii=False)

    def _dump_view(self, model: ViewModel) -> str:
        data = model.to_json()
        data["total"] = self.history.total
        data["first"] = self.history.first
        data["live"] = bool(self.source.live)
        # The scene panel is there for the whole run once it has a picture of its world.
        data["has_scenes"] = self.history.model.scene is not None
        return json.dumps(data, default=str, ensure_ascii=False)

    def scene_svg(self, n: int) -> str | None:
        """The SVG of the scene record number ``n`` (counted from 1; the ``n`` of a view's
        ``scene``), or of the newest scene before it; None if there is none."""
        with self._cond:
            history = self.history
            found = history.slice(n - 1, n)
            if found and found[0].get("kind") == "scene" and isinstance(found[0].get("svg"), str):
                return str(found[0]["svg"])
            scene = history.view_at(n).scene
        return None if scene is None else str(scene["svg"])

    def structure(self, version: int | None = None) -> StateNode | None:
        with self._cond:
            structures = self.history.structures
            data = structures.get(version) if version is not None else None
            if data is None:
                data = self.history.model.structure
        return StateNode.from_dict(data) if data else None

    def records(self, start: int, end: int) -> list[dict[str, Any]]:
        with self._cond:
            end = min(end, start + MAX_RECORDS_PER_REQUEST)
            first = max(start, self.history.first)
            return [
                {"n": first + i, **(_without_svg(r) if r.get("kind") == "scene" else r)}
                for i, r in enumerate(self.history.slice(first, end))
            ]

    def wait_change(self, version: int, timeout: float) -> int:
        with self._cond:
            self._cond.wait_for(lambda: self.version != version or self._closing, timeout)
            return self.version

    @property
    def closing(self) -> bool:
        return self._closing

    # -- lifecycle ---------------------------------------------------------------------------
    def close(self) -> None:
        if self._closing:
            return
        with self._cond:
            self._closing = True
            self._cond.notify_all()
        self._pump_stop.set()
        self._httpd.shutdown()
        self._httpd.server_close()
        for thread in self._threads:
            thread.join(timeout=5)
        self.source.close()

    def __enter__(self) -> ViewerServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def wait(self) -> None:
        """Block until interrupted (Ctrl-C), for command-line use."""
        try:
            while not self._closing:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()


_POLICY = (
    "default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
    "connect-src 'self'; frame-ancestors 'none'"
)
_SCENE_POLICY = "default-src 'none'; style-src 'unsafe-inline'; img-src data:; sandbox"


def _handler_class(viewer: ViewerServer) -> type[BaseHTTPRequestHandler]:
    class Handler(_Handler):
        server_viewer = viewer

    return Handler


class _Handler(BaseHTTPRequestHandler):
    server_viewer: ViewerServer
    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: Any) -> None:
        pass  # quiet: a viewer must not spam the robot's console

    def _host_allowed(self) -> bool:
        viewer = self.server_viewer
        if viewer.host not in LOOPBACK:
            return True  # bound elsewhere on purpose; the user chose who may connect
        host = (self.headers.get("Host") or "").strip()
        name = host.rsplit(":", 1)[0] if not host.endswith("]") else host
        return name in LOOPBACK

    def _send(
        self,
        body: bytes,
        content_type: str,
        status: HTTPStatus = HTTPStatus.OK,
        *,
        policy: str = _POLICY,
    ) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.send_header("Content-Security-Policy", policy)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, data: Any, status: HTTPStatus = HTTPStatus.OK) -> None:
        text = data if isinstance(data, str) else json.dumps(data, default=str, ensure_ascii=False)
        self._send(text.encode("utf-8"), "application/json; charset=utf-8", status)

    def _error(self, status: HTTPStatus, message: str) -> None:
        self._json({"error": message}, status)

    def do_HEAD(self) -> None:
        self.do_GET()

    def do_GET(self) -> None:
        if not self._host_allowed():
            self._error(HTTPStatus.FORBIDDEN, "unexpected Host header")
            return
        url = urlsplit(self.path)
        query = {k: v[-1] for k, v in parse_qs(url.query).items()}
        route: dict[str, Callable[[dict[str, str], str], None]] = {
            "/": self._index,
            "/index.html": self._index,
            "/api/info": self._info,
            "/api/view": self._view,
            "/api/gantt": self._gantt,
            "/api/svg": self._svg,
            "/api/scene": self._scene,
            "/api/records": self._records,
            "/api/export": self._export,
            "/api/stream": self._stream,
            "/api/control": self._control,
        }
        handler = route.get(url.path)
        try:
            if handler is not None:
                handler(query, url.query)
            elif url.path.startswith("/static/") and url.path[8:] in STATIC:
                name = url.path[8:]
                self._send(_static(name), STATIC[name])
            else:
                self._error(HTTPStatus.NOT_FOUND, f"no such page: {url.path}")
        except ValueError as exc:
            self._error(HTTPStatus.BAD_REQUEST, str(exc))
        except (BrokenPipeError, ConnectionResetError):
            pass

    def do_POST(self) -> None:
        if not self._host_allowed():
            self._error(HTTPStatus.FORBIDDEN, "unexpected Host header")
            return
        controls = self.server_viewer.controls
        if controls is None:
            self._error(HTTPStatus.NOT_IMPLEMENTED, "a read-only viewer answers GET only")
            return
        if urlsplit(self.path).path != "/api/control":
            self._error(HTTPStatus.NOT_FOUND, "POST goes to /api/control only")
            return
        try:
            self._json(controls.handle_post(self.headers, self.rfile.read))
        except PermissionError as exc:
            self._error(HTTPStatus.FORBIDDEN, str(exc))
        except ValueError as exc:
            self._error(HTTPStatus.BAD_REQUEST, str(exc))
        except (BrokenPipeError, ConnectionResetError):
            pass

    # -- routes ----------------------------------------------------------------------------------
    def _control(self, query: dict[str, str], raw: str) -> None:
        viewer = self.server_viewer
        if viewer.controls is None:
            self._json({"enabled": False})
            return
        root = viewer.structure()
        paths = [node.path for node in root.walk()] if root is not None else []
        self._json({"enabled": True, **viewer.controls.status(paths)})

    def _index(self, query: dict[str, str], raw: str) -> None:
        self._send(_static("index.html"), "text/html; charset=utf-8")

    def _info(self, query: dict[str, str], raw: str) -> None:
        self._json(self.server_viewer.info())

    def _view(self, query: dict[str, str], raw: str) -> None:
        at = _int(query.get("at"))
        self._json(self.server_viewer.view_json(at))

    def _gantt(self, query: dict[str, str], raw: str) -> None:
        self._json(self.server_viewer.gantt_json(_int(query.get("at"))))

    def _svg(self, query: dict[str, str], raw: str) -> None:
        from smach.introspection.layout import off_path
        from smach.introspection.svg import render_svg

        root = self.server_viewer.structure(_int(query.get("version")))
        if root is None:
            self._send(
                b'<svg xmlns="http://www.w3.org/2000/svg" class="smach-graph" width="300" '
                b'height="40"><text x="10" y="20">no structure yet</text></svg>',
                "image/svg+xml",
            )
            return
        params = parse_qs(raw)
        collapsed = [c for c in params.get("c", []) if c]
        if params.get("focus"):  # the page's default: what is off the active path, collapsed
            collapsed.extend(off_path(root, params.get("a", [])))
        text = render_svg(root, collapsed=collapsed, standalone=False)
        self._send(text.encode("utf-8"), "image/svg+xml")

    def _scene(self, query: dict[str, str], raw: str) -> None:
        n = _int(query.get("n"))
        text = self.server_viewer.scene_svg(self.server_viewer.history.total if n is None else n)
        if text is None:
            self._error(HTTPStatus.NOT_FOUND, "no scene (picture of the world) at that moment")
            return
        # The picture comes from a journal: as a document of its own it runs nothing.
        self._send(text.encode("utf-8"), "image/svg+xml; charset=utf-8", policy=_SCENE_POLICY)

    def _records(self, query: dict[str, str], raw: str) -> None:
        viewer = self.server_viewer
        end = _int(query.get("end"))
        end = viewer.history.total if end is None else end
        start = _int(query.get("start"))
        start = max(0, end - 500) if start is None else start
        self._json(viewer.records(start, end))

    def _export(self, query: dict[str, str], raw: str) -> None:
        from smach.introspection.export import export_view

        viewer = self.server_viewer
        fmt = query.get("format", "svg")
        at = _int(query.get("at"))
        with viewer._cond:
            model = viewer.history.view_at(viewer.history.total if at is None else at)
        text = export_view(model, fmt)
        types = {"svg": "image/svg+xml", "dot": "text/vnd.graphviz", "mermaid": "text/plain"}
        self._send(text.encode("utf-8"), types[fmt] + "; charset=utf-8")

    def _stream(self, query: dict[str, str], raw: str) -> None:
        viewer = self.server_viewer
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream; charset=utf-8")
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.end_headers()
        self.close_connection = True
        sent_total = _int(query.get("since"))
        version = -1
        viewer.clients += 1
        try:
            while not viewer.closing:
                if version == viewer.version:
                    version_now = viewer.wait_change(version, 15.0)
                    if viewer.closing:
                        break
                    if version_now == version:
                        self.wfile.write(b": keep-alive\n\n")
                        self.wfile.flush()
                        continue
                version = viewer.version
                view = viewer.view_json()
                total = viewer.history.total
                start = total - MAX_RECORDS_PER_MESSAGE if sent_total is None else sent_total
                start = max(start, total - MAX_RECORDS_PER_MESSAGE, 0)
                skipped = 0 if sent_total is None else max(0, start - sent_total)
                records = viewer.records(start, total)
                sent_total = total
                records_json = json.dumps(records, default=str, ensure_ascii=False)
                message = f'{{"view":{view},"records":{records_json},"skipped":{skipped}}}'
                self.wfile.write(b"event: update\ndata: " + message.encode("utf-8") + b"\n\n")
                self.wfile.flush()
                # Coalesce: whatever happens during the pause goes out as one update.
                time.sleep(viewer.min_gap)
        except (BrokenPipeError, ConnectionResetError, OSError):
            pass
        finally:
            viewer.clients -= 1


def _without_svg(record: dict[str, Any]) -> dict[str, Any]:
    """A scene record for the timeline: its SVG (``/api/scene``) replaced by its size."""
    svg = record.get("svg")
    light = {k: v for k, v in record.items() if k != "svg"}
    light["svg_bytes"] = len(svg) if isinstance(svg, str) else 0
    return light


def _int(text: str | None) -> int | None:
    if text is None or text == "":
        return None
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"expected a whole number, got {text!r}") from None


def serve(
    root: State | Source,
    port: int = 0,
    host: str = "127.0.0.1",
    *,
    title: str | None = None,
    quiet: bool = False,
    **options: Any,
) -> ViewerServer:
    """Serve the viewer of ``root`` (a container, or any :class:`Source`); print its URL.

    ``port=0`` picks a free port. The server binds ``host`` (loopback by default; any
    other address makes the read-only page reachable from the network, and a warning
    is printed). Returns the running :class:`ViewerServer` (a context manager).
    """
    source: Source = LiveSource(root) if isinstance(root, State) else root
    viewer = ViewerServer(source, host=host, port=port, title=title, **options)
    if not quiet:
        print(f"smach viewer: {viewer.url}", file=sys.stderr, flush=True)
        if host not in LOOPBACK:
            print(
                f"smach viewer: warning: listening on {host}, reachable from other machines",
                file=sys.stderr,
                flush=True,
            )
    return viewer
