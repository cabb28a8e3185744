"""The ``study`` subcommand of ``plan-bridge`` (the work is in :mod:`plan_bridge.study`)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from plan_bridge.cli.base import EXIT_OK, Command, fail
from plan_bridge.study.report import authoring_cost, fault_model, write_report
from plan_bridge.study.runs import (
    APPROACHES,
    DEFAULT_APPROACHES,
    RunSpec,
    inapplicable,
    orders_file,
)
from plan_bridge.study.schedule import read_results, run_study


def _float_list(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}"
        ) from None
    if not values or any(not 0 <= v <= 1 for v in values):
        raise argparse.ArgumentTypeError(f"fault rates must be between 0 and 1: {text!r}")
    return values


def _configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "targets", nargs="+", metavar="TARGET", help="domain folders (domains/NAME)"
    )
    parser.add_argument("--runs", type=int, default=10, help="seeds per configuration (default 10)")
    parser.add_argument("--seeds", help="explicit comma-separated seeds (overrides --runs)")
    parser.add_argument("--fault-rates", type=_float_list, default=[0.0, 0.1, 0.2, 0.4])
    parser.add_argument(
        "--approaches",
        default=",".join(DEFAULT_APPROACHES),
        help=f"comma-separated: {', '.join(APPROACHES)}",
    )
    parser.add_argument(
        "--problem", default="", help="problem name in each folder's problems/ (default: the first)"
    )
    parser.add_argument(
        "--variant", default="", help="a world variant the domains support, e.g. 'unanticipated'"
    )
    parser.add_argument(
        "--orders",
        default="",
        metavar="NAMES",
        help="comma-separated orders files to serve instead of the goal: names of each "
        "folder's orders/NAME.yaml (or paths), e.g. steady,rush (docs/orders.md)",
    )
    parser.add_argument(
        "--out", default="study-results", help="output folder (default study-results)"
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="local worker processes (default: up to 2; not with --cluster)",
    )
    parser.add_argument(
        "--cluster",
        metavar="ADDRESS",
        help="run each run as a Dask task: tcp://HOST:PORT (a running `dask scheduler`) "
        "or local:N (start N local worker processes); needs smach-planner[cluster]",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue the study in --out: skip the runs results.csv already has",
    )
    parser.add_argument(
        "--run-timeout", type=float, default=300.0, help="seconds before a stuck run is killed"
    )


def _run_command(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError

    approaches = [a.strip() for a in args.approaches.split(",") if a.strip()]
    refused = _refused_options(args, approaches)
    if refused is not None:
        return refused
    jobs = args.jobs or max(1, min(2, os.cpu_count() or 1))
    try:
        seeds = [int(s) for s in args.seeds.split(",")] if args.seeds else list(range(args.runs))
    except ValueError:
        return fail(f"--seeds must be comma-separated integers, got {args.seeds!r}")
    streams = [name.strip() for name in args.orders.split(",") if name.strip()] or [""]
    for target in args.targets:
        for name in filter(None, streams):
            try:
                orders_file(str(target), name)
            except ValueError as exc:
                return fail(str(exc))
    skipped = _left_out(args, approaches, serves_orders=streams != [""])
    if isinstance(skipped, int):
        return skipped
    specs = [
        RunSpec(str(t), a, r, s, args.problem, args.variant, o)
        for t in args.targets
        for o in streams
        for a in approaches
        if a not in skipped.get(str(t), [])
        for r in args.fault_rates
        for s in seeds
    ]
    out = Path(args.out)
    written = read_results(out / "results.csv")
    if written and not args.resume:
        return fail(
            f"{out}/results.csv already holds {len(written)} runs: pass --resume to continue "
            "that study (runs it has are skipped), or choose another --out"
        )
    total_runs = len(specs)
    executor = f"Dask cluster {args.cluster}" if args.cluster else f"{jobs} local workers"
    each = f" x {len(streams)} orders files" if streams != [""] else ""
    print(
        f"plan-bridge study: {total_runs} runs ({len(args.targets)} targets{each} x {len(approaches)} approaches x {len(args.fault_rates)} fault rates x {len(seeds)} seeds), {executor}, results in {out}/",
        file=sys.stderr,
        flush=True,
    )
    try:
        rows = run_study(
            specs,
            out,
            jobs=jobs,
            run_timeout=args.run_timeout,
            progress=_progress,
            cluster=args.cluster,
        )
    except (PlanBridgeError, ValueError) as exc:
        return fail(str(exc))
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the rows written so far are kept
        kept = len(read_results(out / "results.csv"))
        print(
            f"\nplan-bridge study: stopped with {kept} of {total_runs} runs in "
            f"{out}/results.csv; the same command with --resume runs the rest",
            file=sys.stderr,
            flush=True,
        )
        raise
    report = _write_report(args, rows, out)
    errors = sum(1 for r in rows if r["outcome"] in ("error", "timeout", "crashed"))
    print(f"{len(rows)} runs ({errors} errors); report: {report}", file=sys.stderr)
    return EXIT_OK if errors == 0 else 1


def _refused_options(args: argparse.Namespace, approaches: list[str]) -> int | None:
    """The exit code for approaches, counts or a cluster that cannot be (None: fine)."""
    unknown = [a for a in approaches if a not in APPROACHES]
    if unknown:
        return fail(f"unknown approaches {unknown}; approaches: {', '.join(APPROACHES)}")
    if args.runs < 1 or (args.jobs is not None and args.jobs < 1):
        return fail("--runs and --jobs must be at least 1")
    if args.cluster:
        from plan_bridge.study.cluster import ClusterError, parse_cluster

        if args.jobs is not None:
            return fail("--jobs is for local runs; with --cluster the cluster's workers run them")
        try:
            parse_cluster(args.cluster)
        except ClusterError as exc:
            return fail(str(exc))
    return None


def _left_out(
    args: argparse.Namespace, approaches: list[str], *, serves_orders: bool = False
) -> dict[str, list[str]] | int:
    """Target -> the approaches that do not apply to it (each said on stderr), or the
    exit code when a target does not load or lacks the scripted baseline asked for (with
    ``serves_orders``: one that serves orders files, ``scripted(..., orders=FILE)``)."""
    import inspect

    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.missions.mission import load_target

    skipped: dict[str, list[str]] = {}
    try:
        for target in args.targets:
            loaded = load_target(target, args.problem or None)
            if "scripted" in approaches and not hasattr(loaded.module, "scripted"):
                return fail(
                    f"{target}: no scripted baseline (scripted() in the domain's Python); drop 'scripted' from --approaches"
                )
            baseline = (
                getattr(loaded.module, "scripted", None) if "scripted" in approaches else None
            )
            if (
                serves_orders
                and baseline is not None
                and "orders" not in inspect.signature(baseline).parameters
            ):
                return fail(
                    f"{target}: its scripted baseline serves no orders files (scripted() has "
                    "no orders= parameter); drop 'scripted' from --approaches"
                )
            for approach in approaches:
                reason = inapplicable(approach, loaded.task)
                if reason:
                    skipped.setdefault(str(target), []).append(approach)
                    print(f"plan-bridge study: {target}: {reason}; left out", file=sys.stderr)
    except PlanBridgeError as exc:
        return fail(str(exc))
    return skipped


def _progress(done: int, total: int, spec: RunSpec, row: dict[str, Any], elapsed: float) -> None:
    width = 24
    filled = int(width * done / total)
    eta = elapsed / done * (total - done)
    orders = f" orders {spec.orders}" if spec.orders else ""
    print(
        f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} "
        f"{Path(spec.target).name}{orders} {spec.approach} p={spec.fault_rate:g} seed {spec.seed}: "
        f"{row['outcome']} ETA {eta:4.0f} s   ",
        end="" if done < total else "\n",
        file=sys.stderr,
        flush=True,
    )


def _write_report(args: argparse.Namespace, rows: list[dict[str, Any]], out: Path) -> Path:
    authoring: list[dict[str, Any]] = []
    fault_models: dict[str, dict[str, float]] = {}
    for target in args.targets:
        authoring += authoring_cost(str(target), args.problem)
        fault_models[Path(target).name] = fault_model(str(target), args.problem)
    # The command that produces these rows: --resume only says how they were collected.
    argv = [a for a in (sys.argv[2:] if len(sys.argv) > 2 else args.targets) if a != "--resume"]
    command = "plan-bridge study " + " ".join(argv)
    return write_report(rows, out, authoring, command, fault_models=fault_models)


COMMANDS = (
    Command(
        "study", "compare scripted and planned missions under faults", _configure, _run_command
    ),
)
