"""The viewer's HTTP server: endpoints, the SSE stream, loopback, bounded buffering."""

from __future__ import annotations

import http.client
import json
import re
import socket
import threading
import time
from importlib import resources
from pathlib import Path
from typing import Any

import pytest
from viewer_machines import chain_machine, demo_machine, wait_until

import smach
from smach.introspection import JournalSource, LiveSource, serve
from smach.introspection.journal import Journal
from smach.introspection.structure import snapshot


def get(viewer: Any, path: str, headers: dict[str, str] | None = None) -> tuple[int, str, str]:
    conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
    conn.request("GET", path, headers=headers or {})
    response = conn.getresponse()
    body = response.read().decode("utf-8")
    conn.close()
    return response.status, response.getheader("Content-Type") or "", body


def read_sse(
    viewer: Any, until: Any = lambda message: False, timeout: float = 10.0
) -> list[dict[str, Any]]:
    """Update messages of the stream, until one satisfies ``until`` (or ``timeout``)."""
    messages: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout
    with socket.create_connection((viewer.host, viewer.port), timeout=0.5) as sock:
        sock.sendall(f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{viewer.port}\r\n\r\n".encode())
        buffer = b""
        while time.monotonic() < deadline:
            try:
                chunk = sock.recv(65536)
            except TimeoutError:
                continue
            if not chunk:
                break
            buffer += chunk
            while b"\n\n" in buffer:
                block, buffer = buffer.split(b"\n\n", 1)
                for line in block.split(b"\n"):
                    if line.startswith(b"data: "):
                        messages.append(json.loads(line[6:]))
                        if until(messages[-1]):
                            return messages
    return messages


@pytest.mark.timeout(30)
def test_serves_on_loopback_by_default_and_prints_the_url(
    capsys: pytest.CaptureFixture[str],
) -> None:
    sm, _ = demo_machine()
    with serve(sm) as viewer:
        assert viewer.host == "127.0.0.1"
        assert viewer.url == f"http://127.0.0.1:{viewer.port}/"
        assert viewer._httpd.server_address[0] == "127.0.0.1"
    assert f"smach viewer: {viewer.url}" in capsys.readouterr().err


@pytest.mark.timeout(30)
def test_page_and_assets_are_self_contained() -> None:
    sm, _ = demo_machine()
    with serve(sm, quiet=True) as viewer:
        status, ctype, html = get(viewer, "/")
        assert status == 200 and ctype.startswith("text/html")
        for asset in re.findall(r'(?:src|href)="(/static/[^"]+)"', html):
            assert get(viewer, asset)[0] == 200
    static = resources.files("smach.introspection") / "static"
    for name in ("index.html", "app.js", "app.css", "graph.css"):
        text = (static / name).read_text("utf-8")
        urls = re.findall(r"https?://[^\s\"'<>)]+", text)
        assert [u for u in urls if u != "http://www.w3.org/2000/svg"] == [], name
        assert "import(" not in text and "@import" not in text


@pytest.mark.timeout(30)
def test_json_endpoints_describe_the_run() -> None:
    sm, hold = demo_machine()
    with serve(sm, quiet=True, interval=0.02) as viewer:
        runner = threading.Thread(target=sm.execute)
        runner.start()
        assert hold["pick"].started.wait(10)
        wait_until(lambda: "/ROOT/FETCH/PICK" in viewer.history.model.active, what="PICK active")
        status, ctype, body = get(viewer, "/api/info")
        info = json.loads(body)
        assert status == 200 and ctype.startswith("application/json")
        assert info["live"] is True and info["controls"] is False
        view = json.loads(get(viewer, "/api/view")[2])
        assert "/ROOT/FETCH/PICK" in view["active"]
        assert view["userdata"]["/ROOT"]["n"] == 1
        records = json.loads(get(viewer, "/api/records?start=0&end=5")[2])
        assert [r["n"] for r in records] == [0, 1, 2, 3, 4]
        records = json.loads(get(viewer, "/api/records")[2])
        start = next(r["n"] for r in records if r["kind"] == "container_started")
        early = json.loads(get(viewer, f"/api/view?at={start + 1}")[2])
        assert early["active"] == ["/ROOT"]
        svg = get(viewer, "/api/svg")[2]
        for node in snapshot(sm).walk():
            assert f'data-path="{node.path}"' in svg
        collapsed = get(viewer, "/api/svg?c=/ROOT/FETCH")[2]
        assert 'data-path="/ROOT/FETCH/PICK"' not in collapsed
        assert get(viewer, "/api/export?format=dot")[2].startswith("digraph")
        assert get(viewer, "/api/view?at=abc")[0] == 400
        hold["pick"].release("picked")
        hold["arm"].release("done")
        hold["base"].go.set()
        runner.join(10)


@pytest.mark.timeout(30)
def test_rejects_foreign_hosts_other_methods_and_unknown_paths() -> None:
    sm, _ = demo_machine()
    with serve(sm, quiet=True) as viewer:
        assert get(viewer, "/api/info", {"Host": "evil.example:80"})[0] == 403
        assert get(viewer, "/api/info", {"Host": f"localhost:{viewer.port}"})[0] == 200
        assert get(viewer, "/static/../server.py")[0] == 404
        assert get(viewer, "/static/source.py")[0] == 404
        assert get(viewer, "/nothing")[0] == 404
        for method in ("POST", "PUT", "DELETE"):
            conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
            conn.request(method, "/api/view", body=b"{}")
            assert conn.getresponse().status == 501
            conn.close()


@pytest.mark.timeout(30)
def test_sse_stream_sends_coalesced_updates_until_the_end() -> None:
    sm, hold = demo_machine()
    with serve(sm, quiet=True, interval=0.02) as viewer:
        got: list[dict[str, Any]] = []
        done = lambda m: m["view"]["root_outcome"] == "done"  # noqa: E731
        reader = threading.Thread(target=lambda: got.extend(read_sse(viewer, done, timeout=10)))
        reader.start()
        wait_until(lambda: viewer.clients == 1, what="client connected")
        hold["pick"].release("picked")
        hold["arm"].release("done")
        hold["base"].go.set()
        assert sm.execute() == "done"
        wait_until(
            lambda: bool(got) and got[-1]["view"]["root_outcome"] == "done", what="final update"
        )
        reader.join(10)
    assert got[0]["view"]["index"] <= got[-1]["view"]["index"]
    seen = [r["n"] for message in got for r in message["records"]]
    assert seen == sorted(seen) and len(seen) == len(set(seen))
    assert seen[-1] == got[-1]["view"]["total"] - 1
    assert got[-1]["view"]["active"] == []


@pytest.mark.timeout(60)
def test_a_client_that_never_reads_does_not_slow_execution() -> None:
    sm = chain_machine(2000)
    viewer = serve(sm, quiet=True, interval=0.01)
    with viewer, socket.create_connection((viewer.host, viewer.port)) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.sendall(f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{viewer.port}\r\n\r\n".encode())
        wait_until(lambda: viewer.clients == 1, what="client connected")
        started = time.monotonic()
        for _ in range(10):
            assert sm.execute() == "finished"
        assert time.monotonic() - started < 20
        # The pump went on folding (the newest events of each poll, then a resync):
        # the view caught up with the end of the run although the client never read.
        wait_until(
            lambda: (
                viewer.history.model.root_outcome == "finished" and not viewer.history.model.running
            ),
            what="the view of the finished run",
        )
        assert viewer.history.total >= 100


def test_live_source_listener_fills_a_bounded_deque() -> None:
    sm = chain_machine(300)
    source = LiveSource(sm, buffer=32)
    # Steps go straight to the deque; single events through the tracker of new machines.
    assert source._listener.capture_many == source._pending.extend
    assert source._listener.capture.queue == source._pending.append
    assert source._listener in sm._bus.listeners
    assert sm._bus.sinks == (source._listener.capture,) and sm._bus.event_listeners == ()
    sm.execute()
    assert len(source._pending) == 32  # the oldest events were dropped, nobody waited
    records = source.poll()
    kinds = [r["kind"] for r in records]
    assert "resync" in kinds
    assert records[kinds.index("resync")]["active"] == []  # the run is over
    assert kinds.count("container_terminated") == 1
    source.close()
    assert source._listener not in sm._bus.listeners


def test_live_source_folds_a_bounded_number_of_events_then_resyncs() -> None:
    sm = chain_machine(300)
    source = LiveSource(sm, max_rate=0.0, burst=10)  # a viewer that never catches up
    sm.execute()
    records = source.poll()
    kinds = [r["kind"] for r in records]
    assert kinds.count("resync") == 1
    events = [r for r in records if r["kind"] not in ("resync", "userdata", "structure")]
    assert len(events) == 10  # the newest ten: the end of the run
    assert events[-1]["kind"] == "container_terminated"
    sm.execute()
    assert [r["kind"] for r in source.poll() if r["kind"] != "userdata"] == ["resync"]
    source.close()


@pytest.mark.timeout(30)
def test_overflow_resyncs_the_active_states_from_the_live_tree() -> None:
    sm, hold = demo_machine()
    source = LiveSource(sm, buffer=4)
    runner = threading.Thread(target=sm.execute)
    runner.start()
    assert hold["pick"].started.wait(10)
    records = source.poll()
    resync = [r for r in records if r["kind"] == "resync"]
    assert resync and resync[-1]["active"] == ["/ROOT", "/ROOT/FETCH", "/ROOT/FETCH/PICK"]
    hold["pick"].release("missed")
    runner.join(10)
    source.close()


@pytest.mark.timeout(30)
def test_live_source_reports_userdata_snapshots_and_structure_changes() -> None:
    from viewer_machines import Trivial

    sm, _hold = demo_machine()
    source = LiveSource(sm, userdata_every=0.0)
    first = [r for r in source.poll() if r["kind"] == "userdata"]
    assert {r["path"] for r in first} == {"/ROOT", "/ROOT/FETCH", "/ROOT/PAR"}
    assert [r for r in source.poll() if r["kind"] == "userdata"] == []  # unchanged: not resent
    sm.userdata.n = 41
    assert [r["values"] for r in source.poll() if r["path"] == "/ROOT"] == [{"n": 41}]
    grown = smach.StateMachine(outcomes=["done"])
    with grown:
        smach.StateMachine.add("A", Trivial(), transitions={"done": "done"})
    live = LiveSource(grown)
    with grown:
        smach.StateMachine.add("B", Trivial(), transitions={"done": "done"})
    grown.set_initial_state(["B"])
    grown.execute()
    kinds = [r["kind"] for r in live.poll()]
    assert kinds[0] == "container_started" and "structure" in kinds
    source.close()
    live.close()


@pytest.mark.timeout(30)
def test_journal_source_replays_and_follows(tmp_path: Path) -> None:
    sm, hold = demo_machine()
    path = tmp_path / "run.jsonl"
    journal = Journal(path, sm, header={"title": "demo run"})
    follow = JournalSource(path, follow=True)
    assert follow.title == "demo run" and follow.live
    assert follow.poll() == []
    hold["pick"].release("picked")
    hold["arm"].release("done")
    hold["base"].go.set()
    sm.execute()
    journal.close()
    records = follow.poll()
    assert (
        records[0]["kind"] == "container_started" and records[-1]["kind"] == "container_terminated"
    )
    with path.open("a") as f:
        f.write('{"kind": "transition", "path": "/ROOT", "source"')  # torn line: not yet
    assert follow.poll() == []
    follow.close()
    replay = JournalSource(path)
    assert not replay.live
    assert len(replay.poll()) == len(records)
    assert replay.poll() == []
    replay.close()
    with serve(JournalSource(path), quiet=True) as viewer:
        view = json.loads(get(viewer, "/api/view")[2])
        assert view["root_outcome"] == "done" and view["total"] == len(records)
        assert json.loads(get(viewer, "/api/info")[2])["live"] is False


def test_serve_refuses_a_plain_state() -> None:
    from viewer_machines import Trivial

    with pytest.raises(TypeError, match="needs a container"):
        serve(Trivial(), quiet=True)
