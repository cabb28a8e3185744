"""``import smach_ros`` for code ported from ROS: a lazy re-export of :mod:`smach.ros`.

Importing it needs nothing beyond ``smach``: ROS 1-era scripts often import
``smach_ros`` but use only core names (or only ``IntrospectionServer`` in a
corner). A name that needs rclpy loads it on first use; without the ``ros``
extra that use raises :class:`ModuleNotFoundError` saying what to install.
``from smach_ros import *`` without rclpy binds stand-ins that raise that same
error when called.
"""

from __future__ import annotations

import importlib.util
from typing import TYPE_CHECKING, Any, NoReturn

import smach.ros

if TYPE_CHECKING:
    from smach.ros import *  # noqa: F403  (the names __getattr__ gives)

_NAMES = tuple(smach.ros.__all__)


def _rclpy_available() -> bool:
    try:
        return importlib.util.find_spec("rclpy") is not None
    except (ImportError, ValueError):
        return False


class _NeedsRos:
    """Stands in for a smach_ros name after ``from smach_ros import *`` without rclpy."""

    def __init__(self, name: str) -> None:
        self._name = name

    def _fail(self) -> NoReturn:
        getattr(smach.ros, self._name)  # raises the ModuleNotFoundError with the hint
        raise ModuleNotFoundError(  # rclpy appeared since the star import
            f"smach_ros.{self._name} was imported with '*' before rclpy was installed; "
            "import it again"
        )

    def __call__(self, *args: Any, **kwargs: Any) -> NoReturn:
        self._fail()

    def __getattr__(self, attribute: str) -> NoReturn:
        if attribute.startswith("__"):
            raise AttributeError(attribute)
        self._fail()

    def __repr__(self) -> str:
        return f"<smach_ros.{self._name}: needs rclpy (pip install 'smach-planner[ros]')>"


def __getattr__(name: str) -> Any:
    if name == "__all__":
        # Looked up by ``from smach_ros import *``: give stand-ins if rclpy is missing.
        if not _rclpy_available():
            for missing in _NAMES:
                globals().setdefault(missing, _NeedsRos(missing))
        return list(_NAMES)
    if name in _NAMES:
        value = getattr(smach.ros, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'smach_ros' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_NAMES])
