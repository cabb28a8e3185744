"""The viewer page in a real headless Chromium (Playwright, Debian's chromium).

Skipped when Playwright or /usr/bin/chromium is missing. Screenshots go to
artifacts/viewer/ (gitignored) for people to look at.
"""

from __future__ import annotations

import itertools
import shutil
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from viewer_machines import ARTIFACTS, big_machine, demo_machine, planned_mission, wait_until

from smach.introspection import JournalSource, serve
from smach.introspection.journal import Journal, read_journal
from smach.introspection.structure import snapshot

pytestmark = pytest.mark.browser

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    if not Path(CHROMIUM).exists():
        pytest.skip("chromium is not installed")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def open_page(browser: Any) -> Iterator[Any]:
    pages: list[Any] = []

    def open_(url: str, width: int = 1400, height: int = 900) -> Any:
        page = browser.new_page(viewport={"width": width, "height": height})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.errors = errors
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=10_000)
        pages.append(page)
        return page

    yield open_
    for page in pages:
        assert page.errors == []
        page.close()


def shot(page: Any, name: str) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"{name}.png"))


def active_paths(page: Any) -> set[str]:
    return set(page.eval_on_selector_all("#graph .active", "els => els.map(e => e.dataset.path)"))


def wait_active(page: Any, expected: set[str], timeout: float = 10.0) -> None:
    wait_until(lambda: active_paths(page) == expected, timeout, f"active states {expected}")


def final_picture(page: Any) -> dict[str, Any]:
    """What the page shows: classes and second lines of every state, status, timeline."""
    nodes = page.eval_on_selector_all(
        "#graph [data-path]",
        """els => els.map(e => [e.dataset.path,
            [...e.classList].filter(c => ['active','visited','preempt','error','reached'].includes(c)).sort().join(' '),
            (e.querySelector('.sub') || {}).textContent || ''])""",
    )
    return {
        "nodes": sorted(map(tuple, nodes)),
        "status": page.inner_text("#status"),
        "transitions": page.eval_on_selector_all(
            "#events tr[data-kind='transition'] td.what", "els => els.map(e => e.textContent)"
        ),
        "userdata": page.inner_text("#ud-table"),
    }


def transitions_in(journal: Path) -> list[str]:
    _, records = read_journal(journal)
    return [
        f"{r['source']} —{r['outcome']}→ {r['target']}"
        for r in records
        if r["kind"] == "transition"
    ]


@pytest.mark.timeout(90)
def test_live_page_follows_nested_and_concurrent_execution_then_replays_the_same(
    open_page: Any, tmp_path: Path
) -> None:
    sm, hold = demo_machine()
    journal_path = tmp_path / "demo.jsonl"
    journal = Journal(journal_path, sm, header={"title": "demo mission"})
    with serve(sm, quiet=True, interval=0.02) as viewer:
        page = open_page(viewer.url)
        # Every state (and container) of the tree is drawn.
        drawn = set(
            page.eval_on_selector_all("#graph [data-path]", "els => els.map(e => e.dataset.path)")
        )
        assert {n.path for n in snapshot(sm).walk()} <= drawn
        runner = threading.Thread(target=sm.execute)
        runner.start()
        assert hold["pick"].started.wait(10)
        wait_active(page, {"/ROOT", "/ROOT/FETCH", "/ROOT/FETCH/PICK"})
        # Userdata of the selected container, live: ROOT first, then FETCH.
        page.wait_for_selector("#ud-table tr[data-key='n'] td.value:text-is('1')")
        page.click("#graph [data-path='/ROOT/FETCH'] .ctitle")
        page.wait_for_selector("#ud-path:text-is('/ROOT/FETCH')")
        page.wait_for_selector("#ud-table tr[data-key='n'] td.value:text-is('2')")
        assert "by NAVIGATE" in page.inner_text("#ud-table")
        shot(page, "live-nested")
        hold["pick"].release("picked")
        assert hold["arm"].started.wait(10) and hold["base"].started.wait(10)
        # Both branches of the Concurrence are active at once.
        wait_active(page, {"/ROOT", "/ROOT/PAR", "/ROOT/PAR/ARM", "/ROOT/PAR/BASE"})
        page.click("#graph [data-path='/ROOT'] .ctitle")
        shot(page, "live-concurrence")
        # A preempt request: ARM stops at once, BASE takes its time; the marker shows.
        sm.request_preempt()
        page.wait_for_selector("#graph .node.preempt[data-path='/ROOT/PAR/BASE']", timeout=10_000)
        assert page.is_visible("#preempt-flag")
        assert page.locator("#graph .badge").count() >= 1
        wait_active(page, {"/ROOT", "/ROOT/PAR", "/ROOT/PAR/BASE"})
        shot(page, "live-preempt")
        hold["base"].go.set()
        runner.join(10)
        journal.close()
        page.wait_for_selector("#status:text-is('outcome: failed')", timeout=10_000)
        wait_active(page, set())
        page.wait_for_selector("#events tr[data-kind='preempt_requested']")
        # The timeline lists the transitions in the order they happened.
        expected = transitions_in(journal_path)
        wait_until(lambda: final_picture(page)["transitions"] == expected, 10, "timeline")
        live_final = final_picture(page)
        shot(page, "live-final")
    # Replay of the journal ends on the same picture.
    with serve(JournalSource(journal_path), quiet=True) as replay:
        page = open_page(replay.url)
        assert page.inner_text("#mode") == "replay"
        assert final_picture(page) == live_final
        shot(page, "replay-final")


@pytest.mark.timeout(90)
def test_replay_slider_and_steps_move_through_the_run(open_page: Any, tmp_path: Path) -> None:
    sm, hold = demo_machine()
    journal_path = tmp_path / "demo.jsonl"
    with Journal(journal_path, sm):
        hold["pick"].release("picked")
        hold["arm"].release("done")
        hold["base"].go.set()
        assert sm.execute() == "done"
    _, records = read_journal(journal_path)
    entered_pick = next(i for i, r in enumerate(records) if r.get("path") == "/ROOT/FETCH/PICK")
    with serve(JournalSource(journal_path), quiet=True) as viewer:
        page = open_page(viewer.url)
        page.wait_for_selector("#status:text-is('outcome: done')")
        assert page.get_attribute("#slider", "max") == str(len(records))
        page.fill("#slider", "0")
        page.wait_for_selector("body[data-index='0']")
        wait_active(page, set())
        page.fill("#slider", str(entered_pick))
        page.wait_for_selector(f"body[data-index='{entered_pick}']")
        page.click("#fwd")
        page.wait_for_selector(f"body[data-index='{entered_pick + 1}']")
        wait_active(page, {"/ROOT", "/ROOT/FETCH", "/ROOT/FETCH/PICK"})
        assert page.inner_text("#status") == "running"
        page.click("#back")
        page.wait_for_selector(f"body[data-index='{entered_pick}']")
        assert "/ROOT/FETCH/PICK" not in active_paths(page)
        page.keyboard.press("ArrowRight")
        page.wait_for_selector(f"body[data-index='{entered_pick + 1}']")
        # A click on a timeline row jumps there.
        page.click("#events tr[data-kind='container_started'] >> nth=0")
        page.wait_for_selector("body[data-index='1']")
        wait_active(page, {"/ROOT"})
        shot(page, "replay-step")


@pytest.mark.timeout(90)
def test_big_graph_shows_every_state_and_collapses_containers(open_page: Any) -> None:
    sm = big_machine()
    tree = snapshot(sm)
    assert sum(1 for _ in tree.walk()) > 50
    with serve(sm, quiet=True, interval=0.02) as viewer:
        page = open_page(viewer.url, 1600, 1000)
        # The default view: the root and its children open, deeper containers boxed.
        assert page.locator("#graph .node.collapsed").count() >= 1
        page.click("#expand-all")
        page.wait_for_selector("#graph .node.collapsed", state="detached")
        drawn = set(
            page.eval_on_selector_all("#graph [data-path]", "els => els.map(e => e.dataset.path)")
        )
        assert {n.path for n in tree.walk()} <= drawn
        assert sm.execute() == "done"
        page.wait_for_selector("#status:text-is('outcome: done')", timeout=10_000)
        assert page.locator("#graph .node.visited").count() >= 50
        page.click("#fit")  # the whole machine in the window (docs/images/viewer-big-graph.png)
        page.wait_for_timeout(200)
        shot(page, "big-graph")
        page.click("#graph [data-path='/ROOT/MISSION'] .toggle")
        page.wait_for_selector("#graph .node.collapsed[data-path='/ROOT/MISSION']")
        assert page.locator("#graph [data-path='/ROOT/MISSION/TASK_0']").count() == 0
        page.click("#graph .node.collapsed[data-path='/ROOT/MISSION']")
        page.wait_for_selector("#graph .cluster[data-path='/ROOT/MISSION']")
        # Zoom in with the wheel: labels become readable.
        page.mouse.move(500, 400)
        for _ in range(4):
            page.mouse.wheel(0, -400)
        page.wait_for_timeout(200)
        shot(page, "big-graph-zoomed")


@pytest.mark.timeout(120)
def test_planned_mission_shows_plans_replans_and_step_status(
    open_page: Any, tmp_path: Path
) -> None:
    pytest.importorskip("unified_planning")
    executive = planned_mission()
    journal_path = tmp_path / "mission.jsonl"
    journal = Journal(journal_path, executive, header={"title": "rooms p01"})
    with serve(executive, quiet=True, interval=0.02, title="rooms p01") as viewer:
        page = open_page(viewer.url)
        assert executive.execute() == "succeeded"
        journal.close()
        page.wait_for_selector("#status:text-is('outcome: succeeded')", timeout=20_000)
        page.wait_for_selector("#plan-columns .plancol >> nth=1")
        columns = page.locator("#plan-columns .plancol")
        assert columns.count() == 2
        assert "previous: plan #1" in columns.nth(0).inner_text()
        assert "current: plan #2" in columns.nth(1).inner_text()
        assert "replan" in columns.nth(1).inner_text()
        assert page.locator("#plan-columns .plancol >> nth=0 >> li.s-aborted").count() == 1
        assert page.locator("#plan-columns .plancol >> nth=1 >> li.s-succeeded").count() == 4
        assert "REPLAN" in page.inner_text(".decisions").upper()
        assert page.locator("#events tr[data-kind='plan_computed']").count() == 2
        shot(page, "plan-live")
    with serve(JournalSource(journal_path), quiet=True) as replay:
        page = open_page(replay.url)
        page.wait_for_selector("#plan-columns .plancol >> nth=1")
        assert page.locator("#plan-columns .plancol").count() == 2
        shot(page, "plan-replay")


def label_boxes(page: Any, selector: str) -> list[dict[str, float]]:
    boxes: list[dict[str, float]] = page.eval_on_selector_all(
        selector,
        "els => els.map(e => { const r = e.getBoundingClientRect();"
        " return {x: r.x, y: r.y, w: r.width, h: r.height}; })",
    )
    return boxes


@pytest.mark.timeout(180)
def test_a_mission_replay_is_readable_at_every_step_by_default(
    open_page: Any, tmp_path: Path
) -> None:
    """Fitted to the window, the running step is open and large, the rest of the plan is
    boxed, the edge labels do not overlap, and what runs is highlighted."""
    pytest.importorskip("unified_planning")
    from plan_bridge.cli import main

    domains = Path(__file__).parents[3] / "domains"
    journal_path = tmp_path / "mission.jsonl"
    main(["run", str(domains / "table_clearing"), "--seed", "1", "--journal", str(journal_path),
          "--quiet"])  # fmt: skip
    _, records = read_journal(journal_path)
    with serve(JournalSource(journal_path), quiet=True) as replay:
        page = open_page(replay.url)
        entered = [
            n + 1
            for n, r in enumerate(records)
            if r["kind"] == "state_entered" and r["path"].count("/") >= 5
        ]
        for index in entered[:: max(1, len(entered) // 6)]:
            page.evaluate(f"seek({index}, true)")
            page.wait_for_selector(f"body[data-index='{index}']")
            wait_until(
                lambda: not page.evaluate("!!window.smachViewer.loadingSvg"), 10, "the layout"
            )
            active = [p for p in active_paths(page) if p.count("/") >= 5]
            assert active, f"nothing highlighted after record {index}"
            heights = [
                b["h"]
                for b in label_boxes(
                    page, "#graph .node.active .label, #graph .cluster.active .ctitle"
                )
            ]
            assert heights and min(heights) >= 8.5, heights  # readable (it was 5 px)
            edges = label_boxes(page, "#graph .edge text")
            for a, b in itertools.combinations(edges, 2):
                assert not (
                    a["x"] < b["x"] + b["w"] - 0.5 and b["x"] < a["x"] + a["w"] - 0.5
                    and a["y"] < b["y"] + b["h"] - 0.5 and b["y"] < a["y"] + a["h"] - 0.5
                ), (a, b)  # fmt: skip
        shot(page, "mission-focus")
