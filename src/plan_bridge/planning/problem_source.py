"""How a task travels to the planner workers: its PDDL text and the names used in it.

A task loaded from PDDL travels as the very text that was read (names come back
unchanged); a task plan_bridge built (a :class:`~plan_bridge.pddl.spec.ProblemSpec`)
as its JSON data, which the worker builds with UP's API; a problem built in code by a
user is written once per task object with UP's PDDLWriter, whose renamings are mapped
back when the plan returns.
"""

from __future__ import annotations

import dataclasses
import json
import threading
import warnings
import weakref
from typing import Any

from plan_bridge.pddl.task import Fact, PlanningTask
from plan_bridge.pddl.up_runtime import lean_copy
from plan_bridge.planning.worker import ProblemText

__all__ = ["problem_source"]

_cache_lock = threading.Lock()


@dataclasses.dataclass(frozen=True)
class _ProblemSource:
    """How a task travels to the workers: its PDDL text and the names used in it."""

    text: ProblemText
    writer: Any = None
    """UP's PDDLWriter, when the text was written from a problem built in code."""
    problem: Any = None
    """The problem the writer wrote (its items map to PDDL names)."""
    notes: tuple[str, ...] = ()

    def pddl_atom(self, fact: Fact) -> list[str]:
        """``fact`` with the names the PDDL text uses."""
        if self.writer is None:
            return list(fact)
        problem, name = self.problem, self.writer.get_pddl_name
        return [name(problem.fluent(fact[0])), *(name(problem.object(a)) for a in fact[1:])]


_written: weakref.WeakKeyDictionary[PlanningTask, _ProblemSource] = weakref.WeakKeyDictionary()


def problem_source(task: PlanningTask) -> _ProblemSource:
    """The text of ``task`` for the workers (written once per task object)."""
    if task.domain_text is not None and task.problem_text is not None:
        # Loaded from PDDL: the worker re-reads the very text we read, so names come
        # back unchanged.
        return _ProblemSource(ProblemText.of(task.domain_text, task.problem_text))
    spec = task.spec
    if spec is not None:
        # Built by plan_bridge: the data goes, never text for UP's reader.
        data = json.dumps(spec.to_json(), separators=(",", ":"))
        return _ProblemSource(ProblemText(spec.domain, "", f"spec-{spec.key}", data))
    with _cache_lock:
        cached = _written.get(task)
    if cached is not None:
        return cached
    from unified_planning.io import PDDLWriter  # type: ignore[import-untyped]

    problem = lean_copy(task.problem)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        writer = PDDLWriter(problem)
        text = ProblemText.of(writer.get_domain(), writer.get_problem())
    source = _ProblemSource(text, writer, problem, tuple(str(w.message) for w in caught))
    with _cache_lock:
        _written[task] = source
    return source
