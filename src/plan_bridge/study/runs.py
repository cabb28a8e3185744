"""The scripted-vs-planned study: run missions under approaches, fault rates and seeds.

``plan-bridge study TARGET... --runs N --fault-rates 0,0.1,0.2,0.4 --out DIR`` runs
every (target, approach, fault rate, seed) and appends one row per finished run to
``DIR/results.csv`` (:mod:`plan_bridge.study.schedule`). This module is one run:
:class:`RunSpec` and :func:`run_one`. A row depends only on its :class:`RunSpec`,
except the columns in :data:`VARYING_FIELDS` (timings, placement).

Approaches: ``scripted`` (the domain's hand-written baseline), ``planned`` (the
executive with the full recovery policy), the ablations ``no-replan``,
``retry-only`` and ``replan-only``, and ``pyperplan`` (full policy, other planner).
The planned approaches plan with ``auto``: Fast Downward on classical problems,
Kairos (then TAMER) on temporal and numeric ones; the ``planner`` column names the
engine that found the plans. Temporal missions play their timeline at
:data:`TEMPORAL_TIME_SCALE` wall seconds per plan second.

A run may serve an **orders file** (``RunSpec.orders``: a file of the target folder's
``orders/``, or a path; see docs/orders.md) instead of the target's goal: the planned
approaches run the order mission (``MissionOptions.orders``), the scripted one calls the
domain's ``scripted(task, ..., orders=FILE)``, whose ``extra["orders"]`` accounts for
the orders as a planned mission does (:class:`OrderAccounts`). The row then holds the
:data:`ORDER_FIELDS` (:func:`order_columns`), and ``goal_reached`` means that every
order that arrived is done, refused or cancelled: none failed, none left open.
"""

from __future__ import annotations

import os
import socket
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from plan_bridge.orders.book import OrderBook

__all__ = [
    "APPROACHES",
    "DEFAULT_APPROACHES",
    "FIELDS",
    "ORDER_FIELDS",
    "VARYING_FIELDS",
    "OrderAccounts",
    "RunSpec",
    "cell_label",
    "cell_number",
    "failure_row",
    "inapplicable",
    "is_temporal",
    "order_columns",
    "orders_file",
    "pin_hash_seed",
    "placement",
    "run_one",
]

APPROACHES: dict[str, tuple[str, str]] = {
    # name: (policy, planner); "scripted" has no planner.
    "scripted": ("", ""),
    "planned": ("full", "auto"),
    "no-replan": ("no-replan", "auto"),
    "retry-only": ("retry-only", "auto"),
    "replan-only": ("replan-only", "auto"),
    "pyperplan": ("full", "pyperplan"),
}
DEFAULT_APPROACHES = tuple(APPROACHES)
#: Wall seconds per plan second of a temporal mission's run. Its steps overlap and
#: wait for each other's ends in real threads: at 0 (no waiting) which thread comes
#: first decides what happens, and a run would not be a function of its seed.
TEMPORAL_TIME_SCALE = 0.01

#: The columns of a run that serves an orders file (empty for the others): orders by
#: what became of them (``lost``: still open at the end, or never arrived), those done
#: the moment they arrived (their goal held already), latency (arrival to done) p50 and
#: p95, orders done per hour of the mission's clock, the robots' mean busy share.
ORDER_FIELDS = [
    "orders_arrived",
    "orders_done",
    "orders_failed",
    "orders_refused",
    "orders_cancelled",
    "orders_lost",
    "orders_late",
    "orders_done_at_arrival",
    "latency_p50_s",
    "latency_p95_s",
    "orders_per_hour",
    "busy_share",
]

FIELDS = [
    "target",
    "problem",
    "variant",
    "orders",
    "approach",
    "fault_rate",
    "seed",
    "outcome",
    "goal_reached",
    "wall_time_s",
    "sim_time_s",
    # What a world that drives a robot reports (pyrobosim: metres driven, battery in
    # percentage points used); empty for the others.
    "distance_m",
    "battery_used",
    *ORDER_FIELDS,
    "steps",
    "actions_executed",
    "actions_failed",
    "faults_injected",
    "retries",
    "continues",
    "repairs",
    "replans",
    "planner_calls",
    "planning_time_s",
    "planner",
    "absorbed_skill",
    "absorbed_retry",
    "absorbed_continue",
    "absorbed_repair",
    "absorbed_replan",
    "error",
    # Where the run ran: the only columns, with the timings, that differ between runs
    # of the same spec (on another worker, machine or cluster).
    "host",
    "worker",
    "cpu_model",
]
#: Columns that may differ between two runs of the same spec; all others may not.
VARYING_FIELDS = ("wall_time_s", "planning_time_s", "host", "worker", "cpu_model")
#: The hash seed of every process that runs the study's runs, and so of the planner
#: processes they start: the planner process breaks ties between equally good plans in
#: hash order (measured: pyperplan on fetch_drink picks another plan with another hash
#: seed), so a run would otherwise depend on the process it ran in, not only its spec.
HASH_SEED = "0"


def inapplicable(approach: str, task: Any) -> str:
    """Why ``approach`` cannot run ``task`` ('' when it can): an approach whose fixed
    engine does not plan problems of the task's kind (pyperplan: classical only)."""
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.planning.engines import engines_for, problem_kind

    planner = APPROACHES[approach][1]
    if planner in ("", "auto"):
        return ""
    try:
        usable = engines_for(task)
    except PlanBridgeError:
        usable = []
    if planner in usable:
        return ""
    return f"approach {approach!r}: {planner} does not plan {problem_kind(task).name} problems"


def pin_hash_seed() -> None:
    """Give the planner processes this process starts from now on a fixed hash seed."""
    os.environ["PYTHONHASHSEED"] = HASH_SEED


#: The columns that name a run, in the order of :attr:`RunSpec.key`.
KEY_FIELDS = ("target", "problem", "variant", "orders", "approach", "fault_rate", "seed")


@dataclass(frozen=True)
class RunSpec:
    """One run of the study."""

    target: str
    approach: str
    fault_rate: float
    seed: int
    problem: str = ""
    variant: str = ""
    orders: str = ""
    """An orders file to serve (a name of the target folder's ``orders/``, or a path);
    "": the target's goal."""

    @property
    def key(self) -> tuple[str, str, str, str, str, str, str]:
        return (
            Path(self.target).name,
            self.problem,
            self.variant,
            self.orders,
            self.approach,
            f"{self.fault_rate:g}",
            str(self.seed),
        )


def orders_file(target: str, name: str) -> Path:
    """The orders file ``name`` of ``target``: ``TARGET/orders/NAME.yaml``, or ``name``
    itself when it is a file. Raises ``ValueError`` naming the files there are."""
    from plan_bridge.pddl.constructs import did_you_mean

    given = Path(name)
    if given.suffix in (".yaml", ".yml") and given.is_file():
        return given
    folder = Path(target) / "orders"
    file = folder / f"{name}.yaml"
    if file.is_file():
        return file
    names = sorted(p.stem for p in folder.glob("*.yaml")) if folder.is_dir() else []
    raise ValueError(
        f"{target}: no orders file {name!r}{did_you_mean(name, names)}; the orders files of "
        f"a target are its orders/NAME.yaml: {', '.join(names) or 'none'} (or give a path)"
    )


class OrderAccounts(Protocol):
    """What accounts for the orders of a run: the planned mission's
    :class:`~plan_bridge.orders.order_executive.OrderExecutive`, a scripted mission's
    ``extra["orders"]`` (e.g. :class:`plan_bridge.robosim.scripting.OrderLedger`)."""

    @property
    def orders(self) -> OrderBook: ...

    def figures(self) -> dict[str, Any]: ...


def order_columns(accounts: OrderAccounts) -> dict[str, Any]:
    """The :data:`ORDER_FIELDS` of a run from what accounts for its orders."""
    figures = accounts.figures()
    states = accounts.orders.states()
    busy = figures.get("busy_share") or {}
    open_ = sum(figures.get(status, 0) for status in ("queued", "assigned", "active"))

    def blank(value: Any) -> Any:
        return "" if value is None else value

    return {
        "orders_arrived": figures["orders"],
        "orders_done": figures["done"],
        "orders_failed": figures["failed"],
        "orders_refused": figures["refused"],
        "orders_cancelled": figures["cancelled"],
        "orders_lost": open_ + figures["not_arrived"],
        "orders_late": figures["late"],
        "orders_done_at_arrival": sum(
            1 for state in states if state.latency is not None and state.latency <= 1e-9
        ),
        "latency_p50_s": blank(figures.get("latency_p50_s")),
        "latency_p95_s": blank(figures.get("latency_p95_s")),
        "orders_per_hour": blank(figures.get("orders_per_hour")),
        "busy_share": round(statistics.fmean(busy.values()), 4) if busy else "",
    }


def orders_accounted(columns: dict[str, Any]) -> bool:
    """Every order that arrived is done, refused or cancelled: none failed, none lost."""
    return not columns["orders_failed"] and not columns["orders_lost"]


def failure_row(spec: RunSpec, outcome: str, error: str, wall_time_s: float) -> dict[str, Any]:
    """The row of a run that did not finish by itself (``timeout``, ``crashed``)."""
    row: dict[str, Any] = dict.fromkeys(FIELDS, "")
    row.update(zip(KEY_FIELDS, spec.key, strict=True))
    row.update(outcome=outcome, goal_reached=False, wall_time_s=round(wall_time_s, 3), error=error)
    return row


# -- one run (in a worker process) ---------------------------------------------------------
_targets: dict[tuple[str, str], Any] = {}


def target_of(path: str, problem: str) -> Any:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.planning.worker import default_pool

    key = (path, problem)
    if key not in _targets:
        _targets[key] = load_target(path, problem or None, prime=default_pool())
    return _targets[key]


def _call_domain(fn: Any, task: Any, spec: RunSpec) -> Any:
    import inspect

    kwargs: dict[str, Any] = {"seed": spec.seed, "fail_rate": spec.fault_rate}
    if spec.variant:
        if "variant" not in inspect.signature(fn).parameters:
            raise ValueError(f"{spec.target}: {fn.__name__}() does not support variants")
        kwargs["variant"] = spec.variant
    if spec.orders:
        if "orders" not in inspect.signature(fn).parameters:
            raise ValueError(f"{spec.target}: {fn.__name__}() does not serve orders files")
        kwargs["orders"] = orders_file(spec.target, spec.orders)
    return fn(task, **kwargs)


def run_one(spec: RunSpec) -> dict[str, Any]:
    """Run one mission and measure it; never raises (errors become rows).

    The row is a function of ``spec`` alone when the planner processes were started
    after :func:`pin_hash_seed` (the study's workers do that first).
    """
    row: dict[str, Any] = dict.fromkeys(FIELDS, "")
    key = spec.key
    row.update(zip(KEY_FIELDS, key, strict=True))
    clock: list[float] = []
    try:
        row.update(_run(spec, clock))
    except Exception as exc:
        row.update(outcome="error", goal_reached=False, error=f"{type(exc).__name__}: {exc}"[:300])
    # Wall time of the mission itself: loading the target is shared by all runs.
    row["wall_time_s"] = round(time.monotonic() - clock[0], 4) if clock else 0.0
    return row


def _count_steps(events: list[Any]) -> int:
    return sum(1 for e in events if e.kind == "state_exited")


_temporal: dict[tuple[str, str], bool] = {}


def is_temporal(path: str, problem: str) -> bool:
    """Whether the target's problem has durative actions (it plays a timeline)."""
    from plan_bridge.planning.engines import problem_kind

    key = (path, problem)
    if key not in _temporal:
        _temporal[key] = problem_kind(target_of(path, problem).task).temporal
    return _temporal[key]


def _run(spec: RunSpec, clock: list[float]) -> dict[str, Any]:
    import smach
    from plan_bridge.missions.runner import MissionOptions, prepare_mission
    from plan_bridge.missions.world_target import WorldTarget

    target = target_of(spec.target, spec.problem)
    task = target.task
    # A pyrobosim world keeps its own simulated time (its clock orders the threads):
    # it runs as fast as it goes, and its sim time is the world's.
    temporal = is_temporal(spec.target, spec.problem) and not isinstance(target, WorldTarget)
    clock.append(time.monotonic())
    exits: list[Any] = []

    def count(event: Any) -> None:
        if event.kind == "state_exited":
            exits.append(event)

    if spec.approach == "scripted":
        scripted = getattr(target.module, "scripted", None)
        if scripted is None:
            raise ValueError(f"{target.name} has no scripted baseline")
        baseline = _call_domain(scripted, task, spec)
        machine = baseline.machine
        if isinstance(machine, smach.Container):
            machine.add_listener(count)
        world = baseline.world
        if temporal:
            world.time_scale = TEMPORAL_TIME_SCALE
        began = time.monotonic()
        outcome = machine.execute()
        numbers = world.figures()
        served = order_columns(baseline.extra["orders"]) if spec.orders else {}
        return {
            **_robot_figures(numbers),
            **served,
            "outcome": outcome,
            "goal_reached": outcome == "succeeded" and orders_accounted(served)
            if spec.orders
            else bool(world.goal_reached()),
            "sim_time_s": round((time.monotonic() - began) / TEMPORAL_TIME_SCALE, 1)
            if temporal
            else numbers.get("sim_time_s", 0.0),
            "steps": _count_steps(exits),
            "actions_executed": numbers.get("actions_run", ""),
            "faults_injected": numbers.get("faults_injected") or 0,
        }
    policy_name, planner_name = APPROACHES[spec.approach]
    options = MissionOptions(
        seed=spec.seed,
        fail_rate=spec.fault_rate,
        planner=planner_name,
        policy=policy_name,
        time_scale=TEMPORAL_TIME_SCALE if temporal else 0.0,
        variant=spec.variant,
        orders=str(orders_file(spec.target, spec.orders)) if spec.orders else None,
    )
    mission = prepare_mission(target, options)
    executive = mission.executive
    executive.add_listener(count)
    outcome = mission.run()
    if mission.error is not None:
        raise RuntimeError(mission.error)
    report = executive.report
    world = mission.world
    figures = world.figures() if world is not None else {}
    faults = int(figures.get("faults_injected") or 0)
    sim_time = figures.get("sim_time_s", 0.0)
    if temporal:
        # The executed makespan (first action's start to last one's end) in plan seconds.
        makespan = mission.timeline.makespan_executed
        sim_time = round((makespan or 0.0) / TEMPORAL_TIME_SCALE, 1)
    decisions = [d["decision"] for d in report.decisions]
    failed = report.actions_failed
    orders: dict[str, Any] = {}
    if spec.orders:
        from plan_bridge.orders.order_executive import OrderExecutive

        assert isinstance(executive, OrderExecutive)
        orders = order_columns(executive)
    reached = (
        outcome == "succeeded" and orders_accounted(orders)
        if spec.orders
        else bool(world.goal_reached())
        if world is not None
        else report.goal_reached
    )
    return {
        **_robot_figures(figures),
        **orders,
        "outcome": outcome,
        "goal_reached": reached,
        "sim_time_s": sim_time,
        "steps": _count_steps(exits),
        "actions_executed": report.actions_executed,
        "actions_failed": failed,
        "faults_injected": faults,
        "retries": report.retries,
        "continues": report.continues,
        "repairs": report.repairs,
        "replans": report.replans,
        "planner_calls": report.planner_calls,
        "planning_time_s": round(report.planning_time_s, 4),
        # The engine(s) that found this run's plans (``auto`` chooses per problem kind).
        "planner": "+".join(sorted(report.planners_won)),
        # Faults that never surfaced as a failed step were absorbed inside the skills
        # (local retries, re-detections); the others by the executive's decisions.
        "absorbed_skill": max(0, faults - failed),
        "absorbed_retry": decisions.count("retry"),
        "absorbed_continue": decisions.count("continue"),
        "absorbed_repair": decisions.count("repair"),
        "absorbed_replan": decisions.count("replan"),
    }


def _robot_figures(figures: dict[str, Any]) -> dict[str, Any]:
    """The columns of a world that drives a robot ('' where the world has no such number)."""
    return {key: figures.get(key, "") for key in ("distance_m", "battery_used")}


def placement(worker: str) -> dict[str, str]:
    """Where a row ran: this machine's host name and CPU model, and the worker."""
    from plan_bridge.study.environment import cpu_model

    return {"host": socket.gethostname(), "worker": worker, "cpu_model": cpu_model()}


def cell_label(target: str, variant: str = "", orders: str = "") -> str:
    """A cell's name in tables and plots: ``robosim_hospital (doors, orders steady)``."""
    more = [*([variant] if variant else []), *([f"orders {orders}"] if orders else [])]
    return f"{target} ({', '.join(more)})" if more else target


def cell_number(value: str) -> float:
    """A cell of ``results.csv`` as a number: 0 when it is empty or not a number."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return 0.0
