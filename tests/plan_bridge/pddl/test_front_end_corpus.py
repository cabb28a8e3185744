"""The front end's corpus: broken and odd-but-valid PDDL files, each with the verdict,
message and line it must get (``;; key: value`` lines at the top of each file).

A file ``domain-*.pddl`` is read with ``corpus/base/problem.pddl`` (or the file named
by ``;; pair:``), a ``problem-*.pddl`` with ``corpus/base/domain.pddl``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from corpus_cases import CORPUS, expectations, pair

from plan_bridge.cli import main
from plan_bridge.cli.base import check_input
from plan_bridge.errors import PddlError, UnsupportedFeatureError
from plan_bridge.pddl.features import is_installed
from plan_bridge.pddl.task import load_task

CASES = sorted(CORPUS.glob("*.pddl"))
BROKEN = [path for path in CASES if ";; verdict: error" in path.read_text("utf-8", "replace")]
VALID = [path for path in CASES if path not in BROKEN]


def engine_missing(meta: dict[str, str]) -> bool:
    engines = meta.get("unless-installed", "").split()
    return bool(engines) and not any(is_installed(name) for name in engines)


def verdict(domain: Path, problem: Path) -> list[str]:
    """What `check`, `plan` and `run` do first: the front end, then UP's reader."""
    warnings = check_input(domain, problem)
    load_task(domain, problem)
    return warnings


def test_the_corpus_has_at_least_60_cases_and_30_broken() -> None:
    assert len(CASES) >= 60
    assert len(BROKEN) >= 30


@pytest.mark.parametrize("path", BROKEN, ids=[p.stem for p in BROKEN])
def test_broken_file_is_refused_at_the_defects_line_with_its_message(path: Path) -> None:
    meta = expectations(path)
    domain, problem = pair(path, meta)
    if meta.get("unless-installed") and not engine_missing(meta):
        verdict(domain, problem)  # an engine is installed: the feature is accepted
        return
    with pytest.raises(PddlError) as caught:
        verdict(domain, problem)
    error = caught.value
    expected_file = domain if meta["where"] == "domain" else problem
    assert error.path == str(expected_file), str(error)
    assert meta["message"] in error.explanation, str(error)
    if meta["line"] == "none":
        assert error.line is None, str(error)
    else:
        assert error.line == int(meta["line"]), str(error)
        assert "^" in error.excerpt
    assert "Traceback" not in str(error)


@pytest.mark.parametrize("path", VALID, ids=[p.stem for p in VALID])
def test_odd_but_valid_file_is_accepted_with_its_warnings(path: Path) -> None:
    meta = expectations(path)
    domain, problem = pair(path, meta)
    if engine_missing(meta):
        with pytest.raises(UnsupportedFeatureError) as caught:
            check_input(domain, problem)
        assert "not installed" in caught.value.explanation
        assert caught.value.line is not None
        load_task(domain, problem)  # the library still reads it
        return
    warnings = verdict(domain, problem)
    if "warning" in meta:
        matching = [w for w in warnings if meta["warning"] in w]
        assert matching, warnings
        if "warning-line" in meta:
            assert any(f":{meta['warning-line']}:" in w.splitlines()[0] for w in matching), matching
    else:
        assert warnings == [], warnings


PLANNED = [p for p in VALID if "plan" in expectations(p)]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("path", PLANNED, ids=[p.stem for p in PLANNED])
def test_odd_but_valid_file_plans_as_it_should(path: Path) -> None:
    from plan_bridge.planning.planner import get_planner

    meta = expectations(path)
    task = load_task(*pair(path, meta))
    result = get_planner("fast-downward").solve(task, timeout=60)
    assert result.solved, result.explanation
    assert len(result.actions) == int(meta["plan"])


@pytest.mark.timeout(120)
@pytest.mark.parametrize("path", BROKEN, ids=[p.stem for p in BROKEN])
def test_check_plan_and_run_give_a_broken_file_the_same_verdict(
    path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meta = expectations(path)
    if meta.get("unless-installed") and not engine_missing(meta):
        pytest.skip("an engine for this feature is installed")
    domain, problem = pair(path, meta)
    messages = []
    for command in ("check", "plan", "run"):
        assert main([command, str(domain), str(problem)]) == 2
        messages.append(capsys.readouterr().err)
    assert messages[0] == messages[1] == messages[2]
    expected_file = domain if meta["where"] == "domain" else problem
    location = f"{expected_file}:{meta['line']}:" if meta["line"] != "none" else f"{expected_file}:"
    assert location in messages[0]
    assert "Traceback" not in messages[0]


@pytest.mark.timeout(300)
@pytest.mark.parametrize("path", PLANNED, ids=[p.stem for p in PLANNED])
def test_check_plan_and_run_accept_an_odd_but_valid_file_alike(
    path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = pair(path, expectations(path))
    warnings = []
    for command in ("check", "plan", "run"):
        assert main([command, str(domain), str(problem)]) == 0, capsys.readouterr().err
        err = capsys.readouterr().err
        assert "error" not in err and "Traceback" not in err
        warnings.append([row for row in err.splitlines() if row.startswith("warning: ")])
    assert warnings[0] == warnings[1] == warnings[2]
