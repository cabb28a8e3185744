"""The viewer's control panel in a real headless Chromium: buttons, breakpoints, the token."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest
from viewer_machines import wait_until

import smach
from smach.control import Controller
from smach.introspection import serve
from smach.introspection.control_api import enable_controls
from smach.testing import BlockingState, ScriptedState

pytestmark = [pytest.mark.browser, pytest.mark.timeout(120)]


def machine() -> tuple[smach.StateMachine, BlockingState]:
    sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "GRASP"})
    grasp = BlockingState(outcomes=("grasped", "missed", "preempted"))
    sm.add("GRASP", grasp, transitions={"grasped": "B", "missed": "failed"})
    sm.add("B", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "done"})
    return sm, grasp


def open_page(browser: Any, url: str) -> Any:
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    page.goto(url)
    page.wait_for_selector("body[data-ready='1']", timeout=10_000)
    page.wait_for_selector("#control-state", timeout=10_000)
    return page


def control_text(page: Any) -> str:
    return str(page.text_content("#control-state") or "")


def test_buttons_and_a_breakpoint_toggle_drive_the_run(browser: Any) -> None:
    sm, grasp = machine()
    ctl = Controller(sm)
    result: list[str | None] = []
    with serve(sm, quiet=True) as viewer:
        url = enable_controls(viewer, ctl)
        page = open_page(browser, url)
        try:
            # A breakpoint on GRASP, set by selecting the node and toggling it.
            page.click('#graph [data-path="/ROOT/GRASP"]')
            page.click("#ctl-bp")
            wait_until(lambda: ctl.breakpoints == ("/ROOT/GRASP",), 10, "breakpoint set")
            wait_until(
                lambda: (
                    page.eval_on_selector_all(".ctl-bp-node", "els => els.map(e => e.dataset.path)")
                    == ["/ROOT/GRASP"]
                ),
                10,
                "breakpoint marked on the node",
            )
            runner = threading.Thread(target=lambda: result.append(sm.execute()), daemon=True)
            runner.start()
            wait_until(lambda: "at breakpoint /ROOT/GRASP" in control_text(page), 10, "held")
            page.click("#ctl-bp")  # toggle it off again
            wait_until(lambda: ctl.breakpoints == (), 10, "breakpoint removed")
            page.click("#ctl-resume")
            assert grasp.started.wait(10)
            # Force the running leaf's outcome from the select box.
            page.wait_for_selector(
                "#ctl-outcome option[value*='grasped']", state="attached", timeout=10_000
            )
            page.select_option("#ctl-outcome", value='["/ROOT/GRASP","grasped"]')
            page.click("#ctl-force")
            runner.join(10)
            assert result == ["done"]
            assert page.errors == []
        finally:
            page.close()
    sources = {(r.action, r.source) for r in ctl.history}
    assert {("add_breakpoint", "viewer"), ("remove_breakpoint", "viewer")} <= sources
    assert {("resume", "viewer"), ("force_outcome", "viewer")} <= sources


def test_pause_step_and_preempt_buttons(browser: Any) -> None:
    sm, grasp = machine()
    ctl = Controller(sm)
    result: list[str | None] = []
    with serve(sm, quiet=True) as viewer:
        page = open_page(browser, enable_controls(viewer, ctl))
        try:
            page.click("#ctl-pause")
            wait_until(lambda: ctl.status().state == "pausing", 10, "pause")
            runner = threading.Thread(target=lambda: result.append(sm.execute()), daemon=True)
            runner.start()
            wait_until(lambda: "paused before /ROOT/A" in control_text(page), 10, "held at A")
            page.click("#ctl-step")
            wait_until(lambda: "paused before /ROOT/GRASP" in control_text(page), 10, "at GRASP")
            page.click("#ctl-preempt")
            runner.join(10)
            assert result == ["preempted"]
            assert grasp.executions == 1
        finally:
            page.close()


def test_without_the_token_the_panel_is_read_only(browser: Any) -> None:
    sm, _ = machine()
    ctl = Controller(sm)
    with serve(sm, quiet=True) as viewer:
        url = enable_controls(viewer, ctl)
        page = open_page(browser, url.split("#")[0])
        try:
            assert page.is_disabled("#ctl-pause")
            assert "read-only" in str(page.text_content("#ctl-message"))
            # Even a request made by the page's own script is refused without the token.
            status = page.evaluate(
                """async () => (await fetch('/api/control', {method: 'POST',
                    headers: {'Content-Type': 'application/json'},
                    body: JSON.stringify({action: 'pause'})})).status"""
            )
            assert status == 403
            assert ctl.status().state == "running"
        finally:
            page.close()


def test_a_read_only_viewer_shows_no_control_panel(browser: Any) -> None:
    sm, _ = machine()
    with serve(sm, quiet=True) as viewer:
        page = browser.new_page()
        try:
            page.goto(viewer.url)
            page.wait_for_selector("body[data-ready='1']", timeout=10_000)
            assert page.query_selector("#control-bar") is None
        finally:
            page.close()


def test_the_replay_shows_control_records_and_the_recorded_control_state(
    browser: Any, tmp_path: Path
) -> None:
    from smach.introspection import JournalSource
    from smach.introspection.journal import Journal

    sm, grasp = machine()
    ctl = Controller(sm)
    path = tmp_path / "run.jsonl"
    with Journal(path, sm) as journal:
        ctl.journal_to(journal)
        ctl.add_breakpoint("/ROOT/GRASP", source="cli")
        result: list[str | None] = []
        runner = threading.Thread(target=lambda: result.append(sm.execute()), daemon=True)
        runner.start()
        assert ctl.wait_for("at_breakpoint", timeout=10)
        ctl.resume(source="viewer")
        assert grasp.started.wait(10)
        ctl.force_outcome("grasped", source="ros")
        runner.join(10)
    assert result == ["done"]
    with serve(JournalSource(path), quiet=True) as viewer:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        try:
            page.goto(viewer.url)
            page.wait_for_selector("body[data-ready='1']", timeout=10_000)
            rows = page.locator("#events tr[data-kind='control']")
            wait_until(lambda: rows.count() == 5, 10, "five control rows in the timeline")
            texts = [str(t) for t in rows.all_text_contents()]
            assert "add_breakpoint (from cli)" in texts[0]
            assert "breakpoint_hit (from machine) → at_breakpoint" in texts[1]
            assert "outcome_forced (from machine)" in texts[4]
            wait_until(
                lambda: (
                    "(last: outcome_forced from machine)"
                    in str(page.text_content("#control-replay") or "")
                ),
                10,
                "the recorded control state",
            )
        finally:
            page.close()
