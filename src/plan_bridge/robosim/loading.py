"""Loading pyrobosim world files: quiet, with clear errors, pyrobosim imported lazily.

pyrobosim logs every step at INFO on loggers named after its world and robots, and its
grasp generator writes to stdout: :func:`load_world_file` turns its loggers down to
WARNING (warnings that matter, such as a path that could not be planned, still show),
and :func:`quiet_stdout` keeps a call's prints out of the command's output.
"""

from __future__ import annotations

import contextlib
import io
import logging
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from plan_bridge.errors import PlanBridgeError

__all__ = ["MISSING", "WorldFileError", "import_pyrobosim", "load_world_file", "quiet_stdout"]

MISSING = (
    "pyrobosim is not installed: pyrobosim worlds need the sim extra "
    "(pip install -e '.[sim]', or ./dev which installs it)"
)
_STDOUT_LOCK = threading.Lock()
#: The seed of what pyrobosim samples while it loads a world file (see load_world_file).
LOAD_SEED = 0


class WorldFileError(PlanBridgeError):
    """A pyrobosim world file that cannot be loaded (or pyrobosim is not installed)."""


def import_pyrobosim() -> Any:
    """The pyrobosim package; :class:`WorldFileError` saying how to install it if absent."""
    try:
        import pyrobosim
        import pyrobosim.core
    except ImportError as exc:
        raise WorldFileError(MISSING) from exc
    return pyrobosim


def load_world_file(path: str | Path) -> Any:
    """A pyrobosim ``World`` loaded from ``path`` (its loggers turned down to WARNING)."""
    import_pyrobosim()
    import yaml
    from pyrobosim.core import WorldYamlLoader

    file = Path(path)
    if not file.is_file():
        raise WorldFileError(f"{file}: no such pyrobosim world file")
    logging.getLogger("pyrobosim").setLevel(logging.WARNING)
    try:
        data = yaml.safe_load(file.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise WorldFileError(f"{file}: not valid YAML: {exc}") from exc
    if not isinstance(data, dict) or not ({"rooms", "robots"} <= set(data)):
        raise WorldFileError(
            f"{file}: not a pyrobosim world file (a YAML mapping with rooms:, robots:, and "
            f"usually hallways:, locations: and objects:)"
        )
    # Its loggers are made (at INFO) while it loads: "Created world." and the like.
    disabled = logging.root.manager.disable
    logging.disable(max(disabled, logging.INFO))
    # pyrobosim samples what a world file leaves open (an object's spawn and pose, a
    # robot's pose at a location, a parent among choices) with numpy's global
    # generator: drawn from a fixed seed, every load of a file is the same world, so
    # the generated problem and the world the run acts on agree (and runs repeat).
    import numpy as np

    outer = np.random.get_state()
    np.random.seed(LOAD_SEED)
    try:
        with quiet_stdout():
            world = WorldYamlLoader().from_file(file)
    except Exception as exc:
        raise WorldFileError(
            f"{file}: pyrobosim could not load the world: {type(exc).__name__}: {exc}"
        ) from exc
    finally:
        np.random.set_state(outer)
        logging.disable(disabled)
    quiet(world)
    stop_sensors(world)
    if not world.robots:
        raise WorldFileError(f"{file}: the world has no robot (robots: - name: robot ...)")
    return world


def quiet(world: Any) -> None:
    """Turn the loggers of ``world`` and its robots down to WARNING."""
    for logger in (world.logger, *(robot.logger for robot in world.robots)):
        logger.setLevel(logging.WARNING)


def stop_sensors(world: Any) -> None:
    """Stop the robots' sensor threads (lidar, field of view) that pyrobosim starts on
    load: the skills do not read them, they cost CPU all run long, and they are not
    daemon threads, so a process would never exit while they run."""
    for robot in world.robots:
        for sensor in robot.sensors.values():
            sensor.stop_thread()


@contextlib.contextmanager
def quiet_stdout() -> Iterator[None]:
    """Swallow what the block prints to stdout (pyrobosim's grasp generator prints)."""
    with _STDOUT_LOCK, contextlib.redirect_stdout(io.StringIO()):
        yield
