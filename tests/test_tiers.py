"""The test tiers (tests/tiers.py): which tier a test lands in, the durations file
kept across runs, one ROS 2 domain per xdist worker."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import tiers

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    ("rel", "marks", "seconds", "tier"),
    [
        ("smach/test_state.py", [], 0.01, "unit"),
        ("smach/test_state.py", [], None, "unit"),  # not recorded yet: counts as quick
        ("smach/test_state.py", [], 1.0, "integration"),
        ("smach/test_state.py", ["slow"], 0.2, "integration"),
        ("smach/ros/test_service_state.py", [], 0.1, "ros"),
        ("plan_bridge/cli/test_goal_option.py", ["ros"], 3.0, "ros"),
        ("plan_bridge/cli/test_view_gantt.py", ["browser"], 3.0, "browser"),
        ("plan_bridge/cli/test_run_output.py", [], 0.1, "cli"),
        ("test_examples.py", [], 5.0, "cli"),
        ("benchmarks/test_core_bench.py", ["slow"], 9.0, "bench"),
        ("plan_bridge/study/test_cluster.py", [], 0.1, "study"),
        ("domains/test_recharge.py", [], 0.1, "mission"),
        ("plan_bridge/robosim/test_snapshot.py", [], 2.0, "mission"),
        ("plan_bridge/clinic/test_x.py", [], 0.1, "unit"),  # a folder, not a name prefix
    ],
)
def test_a_test_lands_in_its_tier(
    rel: str, marks: list[str], seconds: float | None, tier: str
) -> None:
    assert tiers.tier_of(rel, marks, seconds) == tier


def test_every_tier_is_a_registered_marker() -> None:
    text = (ROOT / "pyproject.toml").read_text()
    for name in (*tiers.TIERS, "slow", "serial"):
        assert f'"{name}: ' in text, name


def test_the_xdist_group_suffix_is_taken_off_a_node_id() -> None:
    assert tiers.plain_nodeid("tests/a.py::test_b@serial") == "tests/a.py::test_b"
    assert tiers.plain_nodeid("tests/a.py::t[x]@tests/a.py") == "tests/a.py::t[x]"
    assert tiers.plain_nodeid("tests/a.py::t[x@y]") == "tests/a.py::t[x@y]"


def test_durations_merge_keeps_tests_not_run_and_drops_renamed_ones(tmp_path: Path) -> None:
    (tmp_path / "a.py").write_text("")
    (tmp_path / "b.py").write_text("")
    old = {
        "a.py::kept": 1.5,  # a.py collected, kept's time measured again below
        "a.py::renamed": 2.0,  # a.py collected without it: dropped
        "b.py::not_run": 3.0,  # b.py not collected this time (-m, a path): kept
        "gone.py::t": 4.0,  # the file is gone: dropped
    }
    merged = tiers.merge_durations(
        old, {"a.py::kept": 0.123, "a.py::new": 1.0}, ["a.py::kept", "a.py::new"], tmp_path
    )
    assert merged == {"a.py::kept": 0.12, "a.py::new": 1.0, "b.py::not_run": 3.0}


def test_durations_file_round_trips_one_test_a_line(tmp_path: Path) -> None:
    path = tmp_path / "durations.json"
    tiers.write_durations({"b.py::t": 2.0, "a.py::t[1]": 0.5}, path)
    assert path.read_text() == '{\n  "a.py::t[1]": 0.50,\n  "b.py::t": 2.00\n}\n'
    assert tiers.load_durations(path) == {"a.py::t[1]": 0.5, "b.py::t": 2.0}
    assert json.loads(path.read_text()) == {"a.py::t[1]": 0.5, "b.py::t": 2.0}


def test_an_unreadable_durations_file_counts_every_test_as_not_recorded(
    tmp_path: Path,
) -> None:
    assert tiers.load_durations(tmp_path / "missing.json") == {}
    (tmp_path / "bad.json").write_text("{not json")
    assert tiers.load_durations(tmp_path / "bad.json") == {}


def test_the_committed_durations_file_reads() -> None:
    durations = tiers.load_durations()
    assert durations, "tests/durations.json is missing or empty (./dev test writes it)"
    assert all(seconds >= 0 for seconds in durations.values())


@pytest.mark.parametrize(
    ("base", "worker", "domain"),
    [("150", None, "150"), ("150", "gw0", "150"), ("150", "gw1", "151"), ("232", "gw1", "0")],
)
def test_each_xdist_worker_gets_its_own_ros_domain(
    base: str, worker: str | None, domain: str
) -> None:
    assert tiers.worker_ros_domain({"ROS_DOMAIN_ID": base}, worker) == domain


def test_without_a_ros_domain_one_is_drawn_in_101_to_200() -> None:
    assert 101 <= int(tiers.worker_ros_domain({}, None)) <= 200


@pytest.mark.timeout(120)
def test_a_run_with_store_durations_writes_the_file_and_tiers_select(tmp_path: Path) -> None:
    """A small suite with this conftest: --store-durations writes the file, the next
    collection reads it and puts the slow test out of the unit tier."""
    suite = tmp_path / "tests"
    suite.mkdir()
    (suite / "conftest.py").write_text((ROOT / "tests" / "conftest.py").read_text())
    (suite / "tiers.py").write_text((ROOT / "tests" / "tiers.py").read_text())
    (suite / "test_some.py").write_text(
        "import time\n\n"
        "def test_quick() -> None:\n    assert True\n\n"
        "def test_slow() -> None:\n    time.sleep(1.05)\n"
    )
    durations = tmp_path / "durations.json"
    ini = tmp_path / "pytest.ini"
    markers = "\n".join(f"    {name}: x" for name in (*tiers.TIERS, "slow", "serial"))
    ini.write_text(
        f"[pytest]\naddopts = --strict-markers -p no:cacheprovider\nmarkers =\n{markers}\n"
    )

    def pytest_run(*args: str) -> str:
        done = subprocess.run(
            [sys.executable, "-m", "pytest", "-p", "no:xdist", "-q", *args],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=100,
            check=False,
        )
        assert done.returncode == 0, done.stdout + done.stderr
        return done.stdout

    pytest_run("--store-durations", f"--durations-path={durations}", "tests")
    recorded = tiers.load_durations(durations)
    assert set(recorded) == {"tests/test_some.py::test_quick", "tests/test_some.py::test_slow"}
    assert recorded["tests/test_some.py::test_slow"] >= tiers.SLOW_SECONDS
    selected = pytest_run(
        f"--durations-path={durations}", "--collect-only", "-m", "slow and not unit", "tests"
    )
    assert "tests/test_some.py::test_slow" in selected
    assert "test_quick" not in selected


class FakeDefinition:
    def __init__(self, scope: str) -> None:
        self.scope = scope


class FakeInfo:
    def __init__(self, scopes: dict[str, str]) -> None:
        self.name2fixturedefs = {name: [FakeDefinition(s)] for name, s in scopes.items()}


class FakeItem:
    """What tiers.assign reads of a pytest item and the markers it adds."""

    def __init__(self, rel: str, name: str, scopes: dict[str, str], marks: list[str]) -> None:
        self.path = tiers.TESTS / rel
        self.nodeid = f"tests/{rel}::{name}"
        self._fixtureinfo = FakeInfo(scopes)
        self.added: list[str | pytest.MarkDecorator] = []
        self.marks = [getattr(pytest.mark, mark).mark for mark in marks]

    def iter_markers(self) -> list[pytest.Mark]:
        return self.marks

    def add_marker(self, marker: str | pytest.MarkDecorator) -> None:
        self.added.append(marker)


def groups_of(items: list[FakeItem]) -> list[str | None]:
    found: list[str | None] = []
    for item in items:
        names = [
            m.args[0]
            for m in item.added
            if isinstance(m, pytest.MarkDecorator) and m.name == "xdist_group"
        ]
        found.append(names[0] if names else None)
    return found


def test_tests_sharing_a_module_fixture_go_together_in_runs_of_a_minute_at_most(
    request: pytest.FixtureRequest,
) -> None:
    if not request.config.pluginmanager.hasplugin("xdist"):
        pytest.skip("pytest-xdist is not loaded (its xdist_group marker is needed)")
    module = {"planner": "module"}
    rel = "plan_bridge/planning/test_x.py"
    items = [
        FakeItem(rel, "test_a", module, []),
        FakeItem(rel, "test_b", {"tmp_path": "function"}, []),
        FakeItem(rel, "test_c", module, []),
        FakeItem(rel, "test_d", module, []),
        FakeItem("smach/introspection/test_v.py", "test_page", module, ["browser"]),
        FakeItem("benchmarks/test_b.py", "test_bench", {}, []),
    ]
    seconds = {"test_a": 40.0, "test_b": 5.0, "test_c": 15.0, "test_d": 30.0}
    durations = {item.nodeid: seconds.get(item.nodeid.rsplit("::")[-1], 2.0) for item in items}
    tiers.assign(items, durations, groups=True)  # type: ignore[arg-type]
    module_id = f"tests/{rel}"
    assert groups_of(items) == [
        f"{module_id}#0",  # 40 s
        None,  # no module fixture: handed out on its own
        f"{module_id}#0",  # 55 s so far
        f"{module_id}#1",  # 85 s would be over a minute: a new run
        "serial",  # browser
        "serial",  # bench
    ]
    assert [item.added[0] for item in items] == [
        "integration",
        "integration",
        "integration",
        "integration",
        "browser",
        "bench",
    ]
    assert all("slow" in item.added for item in items)
