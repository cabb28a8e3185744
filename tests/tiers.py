"""Test tiers, assigned in one place (tests/conftest.py calls this module), and the
durations file that sorts the slow tests out of the unit tier.

Every test gets exactly one tier marker:

- by folder: ``ros`` (tests/*/ros/ and any test marked ``ros``), ``browser`` (marked
  ``browser``: headless chromium), ``bench`` (tests/benchmarks: the benchmark scripts at
  smoke size), ``study`` (tests/plan_bridge/study), ``cli`` (tests/plan_bridge/cli, the
  ``./dev`` script and the examples), ``mission`` (tests/domains, tests/plan_bridge/
  missions and robosim: whole missions);
- the rest by measured time: ``unit`` if it took under :data:`UNIT_SECONDS` in the last
  recorded full run (tests/durations.json; a test not recorded yet counts as quick),
  ``integration`` otherwise.

Any test that took :data:`SLOW_SECONDS` or more (or is marked ``slow`` by hand) also
gets ``slow``, whatever its tier.

For pytest-xdist (``--dist loadgroup``): a test that uses a module- or class-scoped
fixture runs on the same worker as the other tests of its module using it (the
fixture is built once, not once per worker), and the ``serial`` tests, the browser
and the bench tiers all run on one worker, one after another (:data:`SERIAL_TIERS`).
"""

from __future__ import annotations

import json
import os
import random
from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DURATIONS_FILE = TESTS / "durations.json"

#: A test at or over this many seconds (setup + call + teardown, as recorded in a full
#: run on workers with coverage on) is out of the unit tier: with 1.0, the unit tier
#: took 66 s on 2 cores; with 0.5, about half (``./dev test --fast``, docs/testing.md).
UNIT_SECONDS = 0.5

#: A test at or over this many seconds also gets the ``slow`` marker.
SLOW_SECONDS = 1.0

#: Tier markers, as registered in pyproject.toml; exactly one per test.
TIERS = ("unit", "integration", "mission", "cli", "ros", "study", "bench", "browser")

#: Tiers given by folder (relative to tests/), checked in this order.
FOLDER_TIERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("ros", ("smach/ros", "plan_bridge/ros")),
    ("bench", ("benchmarks",)),
    ("study", ("plan_bridge/study",)),
    ("cli", ("plan_bridge/cli", "test_dev_script.py", "test_examples.py")),
    ("mission", ("domains", "plan_bridge/missions", "plan_bridge/robosim")),
)

#: Tiers whose tests run one at a time under xdist, with why. They share one xdist
#: group: one worker runs them one after another (their module-scoped fixtures built
#: once) while the other workers go on with the rest.
SERIAL_TIERS: dict[str, str] = {
    "browser": "each starts a headless chromium: two at once on 2 cores crowd out the "
    "page's timers the tests wait on",
    "bench": "the benchmark scripts start process pools of their own and time what they "
    "run; beside each other their reports mean nothing",
}

#: Files or folders (relative to tests/) whose tests run in the serial group too, with
#: why (none today: the tests use free ports, tmp_path and monkeypatch.chdir, and no
#: timing thresholds; a test can also be marked ``serial`` by hand).
SERIAL: dict[str, str] = {}

#: Most recorded seconds of one xdist group of tests sharing a module-scoped fixture.
GROUP_SECONDS = 60.0

#: The ROS 2 domain of each xdist worker is the run's domain plus the worker's number.
ROS_DOMAIN_MAX = 232


def relative(path: Path) -> str:
    """``path`` relative to tests/ with forward slashes ('' when outside tests/)."""
    try:
        return path.resolve().relative_to(TESTS).as_posix()
    except ValueError:
        return ""


def under(rel: str, prefix: str) -> bool:
    return rel == prefix or rel.startswith(prefix + "/")


def folder_tier(rel: str) -> str | None:
    for tier, prefixes in FOLDER_TIERS:
        if any(under(rel, prefix) for prefix in prefixes):
            return tier
    return None


def tier_of(rel: str, marks: Iterable[str], seconds: float | None) -> str:
    """The tier of a test in file ``rel`` (relative to tests/) carrying markers
    ``marks``, which took ``seconds`` in the recorded run (None: not recorded)."""
    names = set(marks)
    if "browser" in names:
        return "browser"
    if "ros" in names:
        return "ros"
    tier = folder_tier(rel)
    if tier is not None:
        return tier
    if "slow" in names or (seconds is not None and seconds >= UNIT_SECONDS):
        return "integration"
    return "unit"


def plain_nodeid(nodeid: str) -> str:
    """The node id without the ``@group`` suffix xdist's loadgroup adds."""
    if "@" in nodeid:
        head, _, tail = nodeid.rpartition("@")
        if not any(c in tail for c in "[]:"):
            return head
    return nodeid


def load_durations(path: Path = DURATIONS_FILE) -> dict[str, float]:
    """{node id: seconds} from the durations file ({} when it is missing or unreadable)."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict):
        return {}
    return {str(k): float(v) for k, v in data.items() if isinstance(v, int | float)}


def merge_durations(
    old: Mapping[str, float],
    measured: Mapping[str, float],
    collected: Iterable[str],
    root: Path = ROOT,
) -> dict[str, float]:
    """The durations to write after a run: ``measured`` over ``old``; old entries of a
    file this run collected but of a test it no longer has, or of a file that is gone,
    are dropped (a test renamed does not leave its old name behind)."""
    collected_ids = set(collected)
    collected_files = {nodeid.split("::", 1)[0] for nodeid in collected_ids}
    merged: dict[str, float] = {}
    for nodeid, seconds in old.items():
        file = nodeid.split("::", 1)[0]
        if file in collected_files and nodeid not in collected_ids:
            continue
        if not (root / file).exists():
            continue
        merged[nodeid] = seconds
    for nodeid, seconds in measured.items():
        merged[nodeid] = round(seconds, 2)
    return dict(sorted(merged.items()))


def write_durations(durations: Mapping[str, float], path: Path = DURATIONS_FILE) -> None:
    """One test a line, sorted, so that a new run's diff shows what changed."""
    lines = [f"  {json.dumps(k)}: {v:.2f}" for k, v in sorted(durations.items())]
    # Written aside, then renamed: a reader (another run's collection) never sees half.
    partial = path.with_name(f".{path.name}.{os.getpid()}")
    partial.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    partial.replace(path)


def worker_ros_domain(environ: Mapping[str, str], worker: str | None) -> str:
    """The ROS 2 domain for this process: the run's (``ROS_DOMAIN_ID``, else random in
    101-200) plus the xdist worker's number (gw0 -> +0, gw1 -> +1, ...), wrapped to
    stay within 0-232; two workers never share a domain."""
    base = int(environ.get("ROS_DOMAIN_ID") or random.randint(101, 200))
    index = int(worker[2:]) if worker and worker.startswith("gw") and worker[2:].isdigit() else 0
    return str((base + index) % (ROS_DOMAIN_MAX + 1))


def uses_scoped_fixture(item: pytest.Item) -> bool:
    """Whether ``item`` uses a module-, class- or package-scoped fixture."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    return any(
        definitions and definitions[-1].scope in ("module", "class", "package")
        for definitions in info.name2fixturedefs.values()
    )


def assign(items: list[pytest.Item], durations: Mapping[str, float], *, groups: bool) -> None:
    """Put every item in its tier, mark the slow ones and, with ``groups`` (xdist is
    loaded), set the xdist groups: the tests of a module sharing a scoped fixture go
    together in runs of up to :data:`GROUP_SECONDS` (a module of 200 s on one worker
    would hold the run up more than building its fixture a few times costs)."""
    chunks: dict[str, tuple[int, float]] = {}  # module -> (chunk number, its seconds)
    for item in items:
        rel = relative(Path(str(item.path)))
        seconds = durations.get(plain_nodeid(item.nodeid))
        marks = {mark.name for mark in item.iter_markers()}
        tier = tier_of(rel, marks, seconds)
        item.add_marker(tier)
        if "slow" not in marks and seconds is not None and seconds >= SLOW_SECONDS:
            item.add_marker("slow")
        if not groups:
            continue
        if (
            "serial" in marks
            or tier in SERIAL_TIERS
            or any(under(rel, prefix) for prefix in SERIAL)
        ):
            item.add_marker(pytest.mark.xdist_group("serial"))
        elif uses_scoped_fixture(item):
            module = item.nodeid.split("::", 1)[0]
            number, total = chunks.get(module, (0, 0.0))
            cost = seconds or 0.0
            if total > 0 and total + cost > GROUP_SECONDS:
                number, total = number + 1, 0.0
            chunks[module] = (number, total + cost)
            item.add_marker(pytest.mark.xdist_group(f"{module}#{number}"))


def xdist_worker() -> str | None:
    return os.environ.get("PYTEST_XDIST_WORKER")


class DurationRecorder:
    """Sums each test's setup, call and teardown seconds and, at the end of the run,
    writes them to the durations file (in the xdist controller, or the only process
    without xdist). A worker sends its collected node ids along with its results, so
    that tests renamed or removed leave the file."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.seconds: dict[str, float] = {}
        self.collected: set[str] = set()

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        nodeid = plain_nodeid(report.nodeid)
        self.seconds[nodeid] = self.seconds.get(nodeid, 0.0) + report.duration

    @pytest.hookimpl(optionalhook=True)
    def pytest_testnodedown(self, node: object, error: object) -> None:
        output = getattr(node, "workeroutput", None) or {}
        self.collected.update(output.get("tiers_collected", ()))

    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        if hasattr(session.config, "workerinput") or not self.seconds:
            return
        merged = merge_durations(load_durations(self.path), self.seconds, self.collected)
        write_durations(merged, self.path)
