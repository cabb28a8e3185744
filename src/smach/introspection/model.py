"""What a viewer shows at one moment, folded from journal records.

Every source of the viewer (a live tree, a journal, a remote executive) delivers
*records*: the dictionaries a :class:`~smach.introspection.journal.Journal` writes,
``{"kind": "transition", "path": ..., "time": ..., ...}``. A :class:`ViewModel`
folds them one by one into the view: active states (every active branch of a
Concurrence), the last outcome of every state, the last transition of every
container, the userdata of every container (bounded summaries), preempt markers,
errors and, for planned missions, the plan panel. The same fold serves the live
page, replay at any event, and exports of a journal at a given time.

Besides the event kinds of :mod:`smach.introspection.events` and of ``plan_bridge``
(recognised by their ``kind`` only: smach does not import plan_bridge), a few
record kinds exist for viewers: ``structure`` (the tree changed), ``userdata``
(a snapshot of a container's userdata) and ``resync`` (the active states read from
the live tree after the viewer dropped events). A ``scene`` record
(:class:`~smach.introspection.events.SceneChanged`: a picture of the world, SVG text)
is kept as the view's :attr:`ViewModel.scene` until the next one. The ``order``
records of a mission of orders (plan_bridge's ``OrderChanged``) make the queue
panel's rows (:attr:`ViewModel.orders`).
"""

from __future__ import annotations

import bisect
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from smach.introspection.compact import structure_of
from smach.introspection.gantt import Timeline, gantt

__all__ = ["History", "ViewModel", "active_at", "fold", "graft"]

MAX_ERRORS = 50
MAX_DECISIONS = 200
MAX_PLANS = 50
MAX_STEPS = 500
MAX_ORDERS = 1000
#: Statuses an order never leaves (plan_bridge.orders.order.FINAL, by name).
FINAL_ORDER_STATUSES = frozenset({"done", "failed", "refused", "cancelled"})


@dataclass
class ViewModel:
    """The folded view; :meth:`apply` one record at a time, :meth:`to_json` to show it."""

    structure: dict[str, Any] | None = None
    structure_version: int = 0
    index: int = 0
    """How many records were folded."""
    time: float | None = None
    t0: float | None = None
    active: dict[str, None] = field(default_factory=dict)
    outcomes: dict[str, str] = field(default_factory=dict)
    entered: dict[str, int] = field(default_factory=dict)
    last_edges: dict[str, list[str]] = field(default_factory=dict)
    userdata: dict[str, dict[str, Any]] = field(default_factory=dict)
    writers: dict[str, dict[str, str]] = field(default_factory=dict)
    preempt: dict[str, str] = field(default_factory=dict)
    errors: list[dict[str, Any]] = field(default_factory=list)
    error_paths: dict[str, str] = field(default_factory=dict)
    root_outcome: str | None = None
    running: bool = False
    resyncs: int = 0
    plans: list[dict[str, Any]] = field(default_factory=list)
    decisions: list[dict[str, Any]] = field(default_factory=list)
    steps: list[dict[str, Any]] = field(default_factory=list)
    running_step: str = ""
    timeline: Timeline = field(default_factory=Timeline)
    """Planned and actual intervals of the actions of temporal plans (the Gantt view)."""
    scene: dict[str, Any] | None = None
    """The newest picture of the world (a ``scene`` record): ``n`` (the record's number,
    counted from 1), ``time``, ``title``, ``path`` and ``svg`` (the SVG text)."""
    orders: dict[str, dict[str, Any]] = field(default_factory=dict)
    """The orders of a mission of orders by id, in arrival order (the queue panel):
    ``id``, ``goal``, ``status``, ``robots``, ``priority``, ``reason``, ``arrived``,
    ``changed`` and ``ended`` (seconds of the mission's clock), ``latency`` (done
    ones). At most :data:`MAX_ORDERS`: the oldest final ones go first."""

    # -- folding ---------------------------------------------------------------------------
    def apply(self, record: Mapping[str, Any]) -> None:
        """Fold one record into the view (unknown kinds only advance the index)."""
        self.index += 1
        kind = record.get("kind")
        t = record.get("time")
        if type(t) is float or isinstance(t, int | float):
            if self.t0 is None:
                self.t0 = float(t)
            self.time = float(t)
        path = record.get("path", "")
        if type(path) is not str:
            path = str(path)
        handler = _HANDLERS.get(kind if type(kind) is str else str(kind))
        if handler is not None:
            handler(self, path, record)

    def _started(self, path: str, record: Mapping[str, Any]) -> None:
        if not self.active or self._is_root(path):
            self.running = True
            self.root_outcome = None
        if self._is_root(path):
            # The root starts again (a resumed run): nothing of the run before is active,
            # even the states a killed process never saw end.
            self.active.clear()
            self.timeline.close(path, None, "interrupted", below=True)
        self.active[path] = None
        self.error_paths.pop(path, None)
        self.timeline.container_started(path)

    def _entered(self, path: str, record: Mapping[str, Any]) -> None:
        self.active[path] = None
        self.entered[path] = self.entered.get(path, 0) + 1
        self.error_paths.pop(path, None)
        self.preempt.pop(path, None)
        parent = path.rsplit("/", 1)[0]
        if self._is_step(parent):
            self.running_step = path

    def _exited(self, path: str, record: Mapping[str, Any]) -> None:
        self._deactivate(path)
        outcome = record.get("outcome")
        if outcome is not None:
            self.outcomes[path] = str(outcome)
        if self.running_step == path:
            self.running_step = ""

    def _transition(self, path: str, record: Mapping[str, Any]) -> None:
        self.last_edges[path] = [
            str(record.get("source", "")),
            str(record.get("outcome", "")),
            str(record.get("target", "")),
        ]

    def _terminated(self, path: str, record: Mapping[str, Any]) -> None:
        self._deactivate(path)
        outcome = record.get("outcome")
        if self.time is not None and self.timeline.actions:
            self.timeline.close(path, self.time, str(outcome))
        if outcome is not None:
            self.outcomes[path] = str(outcome)
        if self._is_root(path) or not self.active:
            self.running = bool(self.active)
            self.root_outcome = None if outcome is None else str(outcome)

    def _error(self, path: str, record: Mapping[str, Any]) -> None:
        message = str(record.get("message", ""))
        self.error_paths[path] = f"{record.get('error_type', 'Error')}: {message}"
        self.errors = [*self.errors[-(MAX_ERRORS - 1) :], {**record}]
        self._deactivate(path)
        if self._is_root(path):
            self.running = False
            self.root_outcome = "error"

    def _preempt_requested(self, path: str, record: Mapping[str, Any]) -> None:
        self.preempt[path] = "requested"

    def _preempt_serviced(self, path: str, record: Mapping[str, Any]) -> None:
        self.preempt[path] = "serviced"

    def _userdata_written(self, path: str, record: Mapping[str, Any]) -> None:
        key = str(record.get("key", ""))
        self.userdata[path] = {**self.userdata.get(path, {}), key: record.get("value")}
        self.writers[path] = {**self.writers.get(path, {}), key: str(record.get("writer", ""))}

    def _userdata_snapshot(self, path: str, record: Mapping[str, Any]) -> None:
        values = record.get("values")
        if isinstance(values, Mapping):
            self.userdata[path] = dict(values)

    def _structure(self, path: str, record: Mapping[str, Any]) -> None:
        tree = structure_of(dict(record))
        if tree is not None:
            self.structure = graft(self.structure, dict(tree), path)
            self.structure_version += 1
            # The machine that was at ``path`` is gone: nothing of it is active any more.
            if path:
                prefix = path + "/"
                for gone in [p for p in self.active if p.startswith(prefix)]:
                    del self.active[gone]

    def _resync(self, path: str, record: Mapping[str, Any]) -> None:
        active = record.get("active")
        if isinstance(active, Sequence):
            self.active = dict.fromkeys(str(p) for p in active)
            self.running = bool(self.active)
        self.resyncs += 1

    def _plan_computed(self, path: str, record: Mapping[str, Any]) -> None:
        steps = [str(s) for s in record.get("steps", ()) or ()]
        plan = {
            "number": len(self.plans) + 1,
            "executive": path,
            "time": record.get("time"),
            "reason": str(record.get("reason", "")),
            "status": str(record.get("status", "")),
            "planner": str(record.get("planner", "")),
            "planning_time_s": record.get("planning_time_s"),
            "explanation": str(record.get("explanation", "")),
            "steps": steps,
            "status_of_steps": ["pending"] * len(steps),
        }
        self.plans = [*self.plans[-(MAX_PLANS - 1) :], plan]

    def _decision(self, path: str, record: Mapping[str, Any]) -> None:
        entry = {
            "time": record.get("time"),
            "decision": str(record.get("decision", "")),
            "reason": str(record.get("reason", "")),
            "step": str(record.get("step", "")),
            "plan": len(self.plans),
        }
        self.decisions = [*self.decisions[-(MAX_DECISIONS - 1) :], entry]

    def _step_finished(self, path: str, record: Mapping[str, Any]) -> None:
        action = str(record.get("action", ""))
        outcome = str(record.get("outcome", ""))
        self.steps = [
            *self.steps[-(MAX_STEPS - 1) :],
            {
                "time": record.get("time"),
                "index": record.get("index"),
                "action": action,
                "outcome": outcome,
                "skill_outcome": str(record.get("skill_outcome", "")),
                "duration_s": record.get("duration_s"),
                "path": path,
                "plan": len(self.plans),
            },
        ]
        # Mark the step in the newest solved plan that lists it and has not seen it yet
        # (a repair runs prefix + rest of the older plan, so match by action text).
        for plan in reversed(self.plans):
            if plan["status"] != "solved":
                continue
            status = plan["status_of_steps"]
            for i, step in enumerate(plan["steps"]):
                if step == action and status[i] in ("pending", "running"):
                    plan["status_of_steps"] = [*status[:i], outcome, *status[i + 1 :]]
                    break
            break

    def _action_started(self, path: str, record: Mapping[str, Any]) -> None:
        self.timeline.started(path, record, len(self.plans))

    def _action_ended(self, path: str, record: Mapping[str, Any]) -> None:
        self.timeline.ended(path, record)

    def _observations(self, path: str, record: Mapping[str, Any]) -> None:
        changed = [str(c) for c in record.get("changed", ()) or ()]
        if self.steps and self.steps[-1]["path"] == path:
            self.steps[-1] = {**self.steps[-1], "observed": changed}

    def _scene(self, path: str, record: Mapping[str, Any]) -> None:
        svg = record.get("svg")
        if isinstance(svg, str) and svg:  # the text is shared with the record, not copied
            self.scene = {
                "n": self.index,
                "time": record.get("time"),
                "title": str(record.get("title", "") or ""),
                "path": path,
                "svg": svg,
            }

    def _order(self, path: str, record: Mapping[str, Any]) -> None:
        name = record.get("order")
        if not isinstance(name, str) or not name:
            return
        status = str(record.get("status", ""))
        at = _seconds(record.get("at"))
        row = self.orders.get(name)
        arrived = row["arrived"] if row is not None else _seconds(record.get("arrived"), at)
        robots = record.get("robots") or ()
        new = {
            "id": name,
            "goal": str(record.get("goal", "")),
            "status": status,
            "robots": [str(r) for r in robots] if isinstance(robots, list | tuple) else [],
            "priority": record.get("priority") or 0,
            "reason": str(record.get("reason", "") or ""),
            "arrived": arrived,
            "changed": at,
        }
        if status in FINAL_ORDER_STATUSES:
            new["ended"] = at
        if status == "done":
            given = _seconds(record.get("latency"))
            latency = given if given is not None else _difference(at, arrived)
            if latency is not None:
                new["latency"] = round(latency, 3)
        # A row is replaced, never changed in place: copies of the view share rows.
        self.orders[name] = new
        if len(self.orders) > MAX_ORDERS:
            final = [k for k, v in self.orders.items() if v["status"] in FINAL_ORDER_STATUSES]
            for gone in (final or list(self.orders))[: len(self.orders) - MAX_ORDERS]:
                del self.orders[gone]

    # -- helpers ------------------------------------------------------------------------------
    def _deactivate(self, path: str) -> None:
        if path in self.active:
            del self.active[path]
        prefix = path + "/"
        stale = [p for p in self.active if p.startswith(prefix)]
        for p in stale:
            del self.active[p]
        if self.preempt.get(path) == "serviced":
            del self.preempt[path]

    def _is_root(self, path: str) -> bool:
        if self.structure is not None:
            return path == self.structure.get("path")
        return path.count("/") <= 1

    def _is_step(self, container: str) -> bool:
        # A plan machine of plan_bridge: its children are labelled 01_ACTION_ARGS.
        return container.endswith("/PLAN")

    # -- output --------------------------------------------------------------------------------
    def copy(self) -> ViewModel:
        """An independent copy (values are never mutated in place, so one level deep)."""
        return ViewModel(
            structure=self.structure,
            structure_version=self.structure_version,
            index=self.index,
            time=self.time,
            t0=self.t0,
            active=dict(self.active),
            outcomes=dict(self.outcomes),
            entered=dict(self.entered),
            last_edges=dict(self.last_edges),
            userdata=dict(self.userdata),
            writers=dict(self.writers),
            preempt=dict(self.preempt),
            errors=list(self.errors),
            error_paths=dict(self.error_paths),
            root_outcome=self.root_outcome,
            running=self.running,
            resyncs=self.resyncs,
            plans=[dict(p) for p in self.plans],
            decisions=list(self.decisions),
            steps=list(self.steps),
            running_step=self.running_step,
            timeline=self.timeline.copy(),
            scene=self.scene,
            orders=dict(self.orders),
        )

    def to_json(self) -> dict[str, Any]:
        """Plain data for the page (structure is sent separately, by version)."""
        return {
            "index": self.index,
            "time": self.time,
            "t0": self.t0,
            "structure_version": self.structure_version,
            "active": list(self.active),
            "outcomes": self.outcomes,
            "entered": self.entered,
            "last_edges": self.last_edges,
            "userdata": self.userdata,
            "writers": self.writers,
            "preempt": self.preempt,
            "errors": self.errors,
            "error_paths": self.error_paths,
            "root_outcome": self.root_outcome,
            "running": self.running,
            "resyncs": self.resyncs,
            "plans": self.plans,
            "decisions": self.decisions,
            "steps": self.steps,
            "running_step": self.running_step,
            "gantt": self._gantt_summary(),
            "scene": self.scene_summary(),
            "orders": list(self.orders.values()),
        }

    def scene_summary(self) -> dict[str, Any] | None:
        """The newest scene without its SVG (a page fetches the SVG when ``n`` changes)."""
        scene = self.scene
        if scene is None:
            return None
        return {**{k: v for k, v in scene.items() if k != "svg"}, "bytes": len(scene["svg"])}

    def _gantt_summary(self) -> dict[str, int] | None:
        actions = self.timeline.actions
        if not actions:
            return None
        return {"rows": len(actions), "running": sum(1 for a in actions if a.ended is None)}

    def gantt_json(self) -> dict[str, Any] | None:
        """The Gantt view's rows at this moment (sent on their own: ``/api/gantt``)."""
        return gantt(self.timeline, self.time)


_HANDLERS = {
    "container_started": ViewModel._started,
    "state_entered": ViewModel._entered,
    "state_exited": ViewModel._exited,
    "transition": ViewModel._transition,
    "container_terminated": ViewModel._terminated,
    "error": ViewModel._error,
    "preempt_requested": ViewModel._preempt_requested,
    "preempt_serviced": ViewModel._preempt_serviced,
    "userdata_written": ViewModel._userdata_written,
    "userdata": ViewModel._userdata_snapshot,
    "structure": ViewModel._structure,
    "resync": ViewModel._resync,
    "plan_computed": ViewModel._plan_computed,
    "executive_decision": ViewModel._decision,
    "step_finished": ViewModel._step_finished,
    "observations_applied": ViewModel._observations,
    "action_started": ViewModel._action_started,
    "action_ended": ViewModel._action_ended,
    "scene": ViewModel._scene,
    "order": ViewModel._order,
}


def _seconds(value: object, default: float | None = None) -> float | None:
    """``value`` as seconds (None, a bool or text: ``default``)."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return default


def _difference(end: float | None, start: float | None) -> float | None:
    return None if end is None or start is None else end - start


def graft(tree: dict[str, Any] | None, subtree: dict[str, Any], path: str = "") -> dict[str, Any]:
    """``tree`` with the node at ``path`` replaced by ``subtree`` (a new tree; ``tree`` is
    not changed). No ``path``, the root's path, or no ``tree``: ``subtree`` is the tree.
    A path whose node is missing is added to its parent's children."""
    if tree is None or not path or path == tree.get("path"):
        return subtree
    if not path.startswith(str(tree.get("path", "")) + "/"):
        return tree  # not part of this tree: keep what is drawn
    return _graft(tree, subtree, path)


def _graft(node: dict[str, Any], subtree: dict[str, Any], path: str) -> dict[str, Any]:
    children = list(node.get("children", ()))
    for i, child in enumerate(children):
        child_path = str(child.get("path", ""))
        if child_path == path:
            children[i] = subtree
            return {**node, "children": children}
        if path.startswith(child_path + "/"):
            children[i] = _graft(child, subtree, path)
            return {**node, "children": children}
    if path.rsplit("/", 1)[0] == node.get("path"):
        return {**node, "is_container": True, "children": [*children, subtree]}
    return node  # its parent is not drawn either


def fold(
    header: Mapping[str, Any], records: Iterable[Mapping[str, Any]], upto: int | None = None
) -> ViewModel:
    """The view after the first ``upto`` records (all when ``None``) of a journal."""
    model = ViewModel()
    tree = header.get("structure")
    if isinstance(tree, Mapping):
        model.structure = dict(tree)
    for n, record in enumerate(records):
        if upto is not None and n >= upto:
            break
        model.apply(record)
    return model


def active_at(
    header: Mapping[str, Any],
    records: Sequence[Mapping[str, Any]],
    *,
    at: float | None = None,
    event: int | None = None,
) -> ViewModel:
    """The view of a journal ``at`` seconds after its first event, or after ``event`` events."""
    if event is not None:
        return fold(header, records, max(0, event))
    if at is not None:
        times = [r.get("time") for r in records]
        t0 = next((t for t in times if isinstance(t, int | float)), None)
        if t0 is None:
            return fold(header, records)
        count = 0
        for n, t in enumerate(times):
            if isinstance(t, int | float) and t - t0 > at:
                break
            count = n + 1
        return fold(header, records, count)
    return fold(header, records)


class History:
    """Records with their folded views, for jumping to any event.

    Keeps at most ``limit`` records (live runs go on for ever); views are checkpointed
    every ``every`` records so that a jump folds at most ``every`` records.
    """

    def __init__(
        self, header: Mapping[str, Any] | None = None, *, limit: int = 50_000, every: int = 256
    ) -> None:
        self.header = dict(header or {})
        self.limit = limit
        self.every = every
        self.model = fold(self.header, ())
        self.records: list[dict[str, Any]] = []
        self.first = 0
        """Index (in the whole run) of ``records[0]``."""
        self._base = self.model.copy()
        self._checkpoints: list[tuple[int, ViewModel]] = []
        self.structures: dict[int, dict[str, Any] | None] = {0: self.model.structure}

    @property
    def total(self) -> int:
        return self.first + len(self.records)

    def add(self, record: dict[str, Any]) -> None:
        model = self.model
        model.apply(record)
        if model.structure_version not in self.structures:
            self.structures[model.structure_version] = model.structure
        records = self.records
        records.append(record)
        total = self.first + len(records)
        if total % self.every == 0:
            self._checkpoints.append((total, model.copy()))
        if len(records) > self.limit:
            self._trim()

    def _trim(self) -> None:
        drop = len(self.records) - self.limit + self.limit // 4
        new_first = self.first + drop
        self._base = self.view_at(new_first)
        del self.records[:drop]
        self.first = new_first
        self._checkpoints = [(n, m) for n, m in self._checkpoints if n > new_first]
        keep = {self._base.structure_version, self.model.structure_version}
        keep.update(m.structure_version for _, m in self._checkpoints)
        self.structures = {v: s for v, s in self.structures.items() if v in keep}

    def view_at(self, index: int) -> ViewModel:
        """The view after ``index`` records of the run (clamped to what is kept)."""
        index = max(self.first, min(index, self.total))
        if index == self.total:
            return self.model.copy()
        keys = [n for n, _ in self._checkpoints]
        pos = bisect.bisect_right(keys, index) - 1
        start, base = self._checkpoints[pos] if pos >= 0 else (self.first, self._base)
        if start < self.first:
            start, base = self.first, self._base
        model = base.copy()
        for record in self.records[start - self.first : index - self.first]:
            model.apply(record)
        return model

    def slice(self, start: int, end: int) -> list[dict[str, Any]]:
        start = max(start, self.first)
        end = min(end, self.total)
        if end <= start:
            return []
        return self.records[start - self.first : end - self.first]
