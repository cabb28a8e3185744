"""The ``skills`` subcommand of ``plan-bridge``: where each action of a domain runs.

For every PDDL action: its parameters and what performs it, the user's skill from
the folder's ``skills.toml`` (factory and ``skills.toml:LINE``), the skill the
domain's ``setup()`` registered, or the simulation (the registry's fallback); and
the variants of each. A folder without Python is listed from the PDDL front end
alone (no unified-planning import); one with a ``setup()`` is loaded as ``run`` does.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    add_input_arguments,
    add_probe_argument,
    check_input,
    fail,
    resolve_input,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from plan_bridge.pddl.task import ActionSchema
    from plan_bridge.skills.registry import SkillRegistry
    from plan_bridge.skills.skill_map import SkillMap

__all__ = ["ActionBinding", "Binding"]

#: Where a skill comes from (``runs`` in ``--json``).
SKILL_MAP, DOMAIN, SIMULATED, NONE = "skill-map", "domain", "simulated", "none"


@dataclass(frozen=True)
class Binding:
    """What performs an action (or one variant of it)."""

    runs: str
    """:data:`SKILL_MAP`, :data:`DOMAIN`, :data:`SIMULATED` or :data:`NONE`."""
    factory: str = ""
    line: int | None = None
    """The entry's line in the skill map."""
    arguments: list[Any] | None = None
    outcome_map: dict[str, str] = field(default_factory=dict)
    variant: str = ""
    ros: dict[str, Any] | None = None
    """A ROS entry's ``kind``, ``name`` and ``type`` (None: a factory)."""

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "runs": self.runs,
            "factory": self.factory or None,
            "line": self.line,
            "arguments": self.arguments,
            "outcome_map": self.outcome_map,
        }
        if self.ros is not None:
            data["ros"] = self.ros
        if self.variant:
            data = {"variant": self.variant, **data}
        return data

    def describe(self, map_name: str) -> str:
        if self.runs == SIMULATED:
            return "simulated (fallback)"
        if self.runs == NONE:
            return "no skill (and no fallback): `plan-bridge check` fails"
        text = f"{'your skill' if self.runs == SKILL_MAP else 'domain skill'} {self.factory}"
        if self.ros is not None:
            text = f"ROS {self.ros['kind']} {self.ros['name']} ({self.ros['type']})"
        if self.arguments is not None:
            text += f"({', '.join(str(a) for a in self.arguments)})"
        if self.outcome_map:
            text += "  outcomes " + ", ".join(f"{k}->{v}" for k, v in self.outcome_map.items())
        if self.line is not None:
            text += f"  [{map_name}:{self.line}]"
        return text


@dataclass(frozen=True)
class ActionBinding:
    """One PDDL action, its parameters and what performs it."""

    action: str
    parameters: list[tuple[str, str]]
    """(``?name``, type) in PDDL order."""
    main: Binding
    variants: list[Binding]

    def to_json(self) -> dict[str, Any]:
        return {
            "action": self.action,
            "parameters": [{"name": n, "type": t} for n, t in self.parameters],
            **self.main.to_json(),
            "variants": [variant.to_json() for variant in self.variants],
        }


def bindings(
    actions: Mapping[str, ActionSchema],
    registry: SkillRegistry,
    skill_map: SkillMap | None,
    *,
    package: str = "",
    folder_name: str = "",
    fallback: bool | None = None,
) -> list[ActionBinding]:
    """What performs each of ``actions`` (in domain order) with ``registry``, the map's
    entries told apart from the domain's skills. ``package``: the domain package's
    module name, shown as ``folder_name``; ``fallback``: whether actions without a skill
    are simulated (default: whether ``registry`` has a fallback)."""
    simulated = registry.fallback is not None if fallback is None else fallback
    from plan_bridge.skills.skill_map_model import describe_factory, registered_skill

    def name_of(factory: object) -> str:
        text = describe_factory(factory)
        if package and (text.startswith((f"{package}:", f"{package}."))):
            text = folder_name + text[len(package) :]
        return text

    def binding(action: str, variant: str = "") -> Binding:
        entry = skill_map.entry(action, variant) if skill_map is not None else None
        if entry is not None:
            ros = entry.ros
            return Binding(
                SKILL_MAP,
                entry.target,
                entry.line,
                None if entry.arguments is None else list(entry.arguments),
                dict(entry.outcome_map),
                variant,
                None
                if ros is None
                else {"kind": ros.kind, "name": ros.name, "type": ros.type_name},
            )
        skill = registered_skill(registry, action, variant)
        if skill is not None:
            return Binding(
                DOMAIN, name_of(skill.factory), outcome_map=dict(skill.outcome_map), variant=variant
            )
        return Binding(SIMULATED if simulated else NONE)

    return [
        ActionBinding(
            name,
            [("?" + p.name.lstrip("?"), p.type) for p in schema.parameters],
            binding(name),
            [binding(name, variant) for variant in registry.variants(name)],
        )
        for name, schema in actions.items()
    ]


def _configure(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    add_probe_argument(parser)


@dataclass(frozen=True)
class _FrontEndActions:
    """The domain's actions and the problem's objects, from the PDDL front end."""

    actions: Mapping[str, ActionSchema]
    objects: Mapping[str, str]
    """Object (and constant) name -> its type."""
    is_subtype: Callable[[str, str], bool]

    def objects_of_type(self, type_name: str) -> tuple[str, ...]:
        return tuple(
            name for name, kind in self.objects.items() if self.is_subtype(kind, type_name)
        )


def _run(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError

    try:
        chosen = resolve_input(args)
        domain, problem = chosen.domain, chosen.problems[0]
        check_input(domain, problem).show()
        listed = _list(args, chosen.folder, domain, problem, world=chosen.world is not None)
    except (InputError, PlanBridgeError) as exc:
        return fail(str(exc))
    name, skill_map, rows, task = listed
    map_path = None if skill_map is None else skill_map.path
    unready: list[str] = []
    if args.probe is not None:
        from plan_bridge.skills.ros.probe import print_probe

        unready = print_probe(skill_map, task, args.probe)
    if args.json:
        payload = {
            "target": name,
            "domain": str(domain),
            "problem": str(problem),
            "skill_map": None if map_path is None else str(map_path),
            "actions": [row.to_json() for row in rows],
        }
        print(json.dumps(payload, indent=None))
        return EXIT_FAILED if unready else EXIT_OK
    map_name = map_path.name if map_path is not None else ""
    out = sys.stdout
    print(
        f"{name}: {len(rows)} actions (problem {problem.name}; skill map: "
        f"{map_path if map_path is not None else 'none'})",
        file=out,
    )
    for row in rows:
        parameters = ", ".join(f"{n} - {t}" for n, t in row.parameters)
        print(f"{row.action}({parameters})", file=out)
        print(f"    {row.main.describe(map_name)}", file=out)
        for variant in row.variants:
            print(f"    variant {variant.variant}: {variant.describe(map_name)}", file=out)
    counts = {
        kind: sum(1 for row in rows if row.main.runs == kind)
        for kind in (SKILL_MAP, DOMAIN, SIMULATED, NONE)
    }
    print(
        f"{counts[SKILL_MAP]} from the skill map, {counts[DOMAIN]} domain skills, "
        f"{counts[SIMULATED]} simulated"
        + (f", {counts[NONE]} without a skill" if counts[NONE] else ""),
        file=out,
    )
    if unready:
        return fail(f"{len(unready)} ROS server(s) of the skill map not ready", EXIT_FAILED)
    return EXIT_OK


def _list(
    args: argparse.Namespace,
    folder: Path | None,
    domain: Path,
    problem: Path,
    *,
    world: bool = False,
) -> tuple[str, SkillMap | None, list[ActionBinding], Any]:
    """(target name, its skill map, the bindings, the task they were checked against)
    of the input."""
    from plan_bridge.skills.registry import SkillRegistry
    from plan_bridge.skills.skill_map import find_skill_map, load_skill_map

    has_python = folder is not None and any(
        (folder / entry).is_file() for entry in ("__init__.py", "skills.py")
    )
    if not has_python and not world:
        # Symbolic skills and the map only: the front end's actions suffice.
        from plan_bridge.pddl.front_end import analyse_files
        from plan_bridge.pddl.task import ActionSchema, Parameter

        front = analyse_files(domain, problem)
        model = front.domain_model
        objects = {
            name: entry.type
            for declared in (model.constants, front.problem_model.objects)
            for name, entry in declared.items()
        }
        actions = {
            action.name: ActionSchema(
                action.name, tuple(Parameter(p.name.lstrip("?"), p.type) for p in action.params)
            )
            for action in model.actions
        }
        registry = SkillRegistry()
        map_path = find_skill_map(folder) if folder is not None else None
        skill_map = None
        task = _FrontEndActions(actions, objects, model.is_subtype)
        if map_path is not None:
            skill_map = load_skill_map(map_path, task)
            skill_map.apply(registry)
        name = folder.name if folder is not None else domain.stem
        return name, skill_map, bindings(actions, registry, skill_map, fallback=True), task

    from plan_bridge.missions.mission import load_target

    target = load_target(args.target, problem, goal=args.goal)
    setup = target.setup(seed=0, fail_rate=0.0)
    found = setup.extra.get("skill_map")
    package = target.module.__name__ if target.module is not None else ""
    rows = bindings(
        target.task.actions, setup.skills, found, package=package, folder_name=target.name
    )
    return target.name, found, rows, target.task


COMMANDS = (
    Command(
        name="skills",
        help="list each action of a domain and the skill that performs it",
        description="For every PDDL action of TARGET (a domain folder, or DOMAIN PROBLEM): "
        "its parameters and what performs it: your skill from the folder's skills.toml "
        "(factory and skills.toml:LINE), the domain's registered skill, or the simulation "
        "(fallback); variants too; a ROS entry of skills.toml as the action, service or topic it "
        "calls. A bad skill map: exit 2 with the file:line of each problem; with --probe, exit 1 "
        "when a ROS server of the map is not up.",
        configure=_configure,
        run=_run,
    ),
)
