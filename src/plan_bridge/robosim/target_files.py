"""Which targets are pyrobosim worlds, and the goals of a world folder (no pyrobosim).

A target is a pyrobosim world when it is a ``.yaml``/``.yml`` file, or a folder with a
``world.yaml`` (and no ``domain.pddl``). A world folder may hold ``goals.yaml``: named
goals in pyrobosim's vocabulary, the first the default (``--problem NAME`` picks one)::

    fetch_apple: (At apple0 table_tabletop)
    charge: (and (At robot charger_dock) (HandEmpty robot))
"""

from __future__ import annotations

from pathlib import Path

from plan_bridge.errors import PlanBridgeError

__all__ = [
    "DOMAIN_PATH",
    "GOALS_FILE",
    "WORLD_FILE",
    "WORLD_SUFFIXES",
    "read_goals",
    "world_file_of",
]

DOMAIN_PATH = Path(__file__).parents[1] / "maps" / "domain.pddl"
"""The map domain shipped with plan_bridge (the task level of pyrobosim worlds)."""
WORLD_FILE = "world.yaml"
GOALS_FILE = "goals.yaml"
WORLD_SUFFIXES = (".yaml", ".yml")


def world_file_of(target: str | Path) -> Path | None:
    """The pyrobosim world file of ``target``, or None when it is not a world."""
    path = Path(target)
    if path.is_file() and path.suffix.lower() in WORLD_SUFFIXES:
        return path
    if path.is_dir() and (path / WORLD_FILE).is_file() and not (path / "domain.pddl").exists():
        return path / WORLD_FILE
    return None


def read_goals(folder: Path) -> dict[str, str]:
    """The named goals of a world folder's ``goals.yaml`` (empty without one)."""
    file = folder / GOALS_FILE
    if not file.is_file():
        return {}
    try:
        import yaml
    except ImportError as exc:  # PyYAML comes with pyrobosim (the sim extra)
        raise PlanBridgeError(
            f"{file}: reading it needs PyYAML, which the sim extra installs "
            f"(pip install -e '.[sim]')"
        ) from exc
    try:
        data = yaml.safe_load(file.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise PlanBridgeError(f"{file}: cannot read the goals: {exc}") from exc
    if not isinstance(data, dict) or not all(
        isinstance(k, str) and isinstance(v, str) for k, v in data.items()
    ):
        raise PlanBridgeError(
            f"{file}: goals must be a YAML mapping NAME: GOAL, e.g. "
            f"fetch_apple: (At apple0 table0_tabletop)"
        )
    return dict(data)
