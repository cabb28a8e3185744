"""smach: hierarchical concurrent state machines for robot task execution.

API-compatible with the original SMACH (ros/executive_smach), strict where the
original silently lost data or hung, and fast. Pure Python, no ROS.
"""

from __future__ import annotations

import sys
import types
from typing import TYPE_CHECKING, Any

from smach import (
    concurrence,
    container,
    exceptions,
    iterator,
    log,
    sequence,
    state,
    state_machine,
    user_data,
    util,
)
from smach.concurrence import Concurrence
from smach.container import Container
from smach.exceptions import (
    InvalidConstructionError,
    InvalidStateError,
    InvalidTransitionError,
    InvalidUserCodeError,
    SmachError,
)
from smach.introspection.render import to_dot, to_mermaid
from smach.introspection.structure import StateNode, snapshot
from smach.iterator import Iterator
from smach.log import loggers, set_loggers
from smach.retry import Retry
from smach.sequence import Sequence
from smach.state import CBState, State
from smach.state_machine import StateMachine
from smach.timeout import Timeout
from smach.user_data import Remapper, UserData
from smach.util import (
    CBInterface,
    cb_interface,
    has_smach_interface,
    set_shutdown_check,
    shutdown,
)
from smach.validation import ValidationReport, validate
from smach.wrapper import Wrapper

if TYPE_CHECKING:
    # At run time these five are properties of the module's type (below).
    from smach.log import logdebug, logerr, loginfo, logwarn
    from smach.util import is_shutdown

__version__ = "0.1.0"

__all__ = [
    "CBInterface",
    "CBState",
    "Concurrence",
    "Container",
    "InvalidConstructionError",
    "InvalidStateError",
    "InvalidTransitionError",
    "InvalidUserCodeError",
    "Iterator",
    "Remapper",
    "Retry",
    "Sequence",
    "SmachError",
    "State",
    "StateMachine",
    "StateNode",
    "Timeout",
    "UserData",
    "ValidationReport",
    "Wrapper",
    "cb_interface",
    "concurrence",
    "container",
    "exceptions",
    "has_smach_interface",
    "is_shutdown",
    "iterator",
    "log",
    "logdebug",
    "logerr",
    "loginfo",
    "logwarn",
    "sequence",
    "set_loggers",
    "set_shutdown_check",
    "snapshot",
    "state",
    "state_machine",
    "to_dot",
    "to_mermaid",
    "user_data",
    "util",
    "validate",
]


def _view(holder: Any, attribute: str) -> property:
    def get(_module: types.ModuleType) -> Any:
        return getattr(holder, attribute)

    def set_(_module: types.ModuleType, value: Any) -> None:
        setattr(holder, attribute, value)

    return property(get, set_, doc=f"smach's {attribute} (assignable)")


class _Smach(types.ModuleType):
    """The type of the ``smach`` module. Its loggers and its shutdown check are views
    of :data:`smach.log.loggers` and :data:`smach.util.shutdown`: reading or assigning
    ``smach.loginfo`` (or ``logwarn``, ``logdebug``, ``logerr``, ``is_shutdown``), as
    code written for the original SMACH does, reads or replaces what every module of
    smach calls, and none of those modules imports this package to find it."""

    loginfo = _view(loggers, "loginfo")
    logwarn = _view(loggers, "logwarn")
    logdebug = _view(loggers, "logdebug")
    logerr = _view(loggers, "logerr")
    is_shutdown = _view(shutdown, "check")


sys.modules[__name__].__class__ = _Smach
