"""Skill maps: a ``skills.toml`` file that binds PDDL actions to skill factories.

A domain folder's ``skills.toml`` says which actions run as the user's own skills;
every other action keeps the registry's fallback (simulated). No Python setup code
is needed::

    # skills.toml
    [move]                                    # a PDDL action of domain.pddl
    factory = "my_skills:make_move"           # "module:callable"
    arguments = ["?r", "?to"]                 # optional: what the factory gets, in order
    outcome_map = { arrived = "succeeded", blocked = "aborted" }   # optional

    pick = "my_skills:make_pick"              # short form: just the factory

    [[place]]                                 # [[action]]: several entries for one action,
    factory = "my_skills:make_place"          # at most one without a variant (the main skill)
    [[place]]
    factory = "my_skills:make_careful_place"
    variant = "careful"

Modules are looked up in the map's folder first (``my_skills`` is ``my_skills.py``
or ``my_skills/`` next to ``skills.toml``, imported as part of the domain's package,
so it can import its siblings with ``from . import helpers``), then among installed
modules. ``arguments`` lists ``?parameter`` names of the action and constants (a
string without ``?``, a number or a boolean), passed as they are.

:func:`load_skill_map` reads, checks and resolves a map (every problem reported at
once, each as ``skills.toml:LINE: ...``, as a :class:`SkillMapError`);
:meth:`SkillMap.apply` registers its entries in a
:class:`~plan_bridge.skills.registry.SkillRegistry` as the user's own skills
(``simulated=False``). :meth:`plan_bridge.missions.mission.Target.setup` applies a
domain folder's ``skills.toml`` on its own.

The map's types are in :mod:`~plan_bridge.skills.skill_map_model` (those
:func:`load_skill_map` returns and raises are re-exported here); the checks of each entry in :mod:`~plan_bridge.skills.skill_map_checks`;
reading the TOML with line positions and importing factories in
:mod:`~plan_bridge.skills.skill_map_source`.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

from plan_bridge.skills.skill_map_checks import check_skill_map
from plan_bridge.skills.skill_map_model import (
    MAP_FILE,
    HasActions,
    MapProblem,
    SkillMap,
    SkillMapEntry,
    SkillMapError,
)

# The map and its error are re-exported: what load_skill_map returns and raises.
__all__ = [
    "MapProblem",
    "SkillMap",
    "SkillMapEntry",
    "SkillMapError",
    "find_skill_map",
    "load_skill_map",
]


def find_skill_map(folder: str | Path) -> Path | None:
    """The folder's ``skills.toml``, if it has one."""
    path = Path(folder) / MAP_FILE
    return path if path.is_file() else None


# -- loading ---------------------------------------------------------------------------


def load_skill_map(
    path: str | Path, task: HasActions, *, package: ModuleType | None = None
) -> SkillMap:
    """Read, check and resolve the skill map at ``path`` (a file, or a folder with a
    ``skills.toml``) against ``task``'s actions.

    Factories are imported now: modules are looked up in the map's folder first (as
    submodules of ``package``, the domain folder's package, when given; else of the
    package already loaded for that folder, or of a new empty one), then among
    installed modules. Raises :class:`SkillMapError` with every problem found.
    """
    path = Path(path)
    if path.is_dir():
        path = path / MAP_FILE
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise SkillMapError([MapProblem(str(path), None, "no such skill map file")]) from None
    except UnicodeDecodeError as exc:
        raise SkillMapError(
            [MapProblem(str(path), None, f"not UTF-8 text ({exc.reason} at byte {exc.start})")]
        ) from None
    except OSError as exc:
        raise SkillMapError([MapProblem(str(path), None, exc.strerror or str(exc))]) from None
    return check_skill_map(path, text, task, package)
