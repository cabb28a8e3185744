"""smach: hierarchical concurrent state machines for robot task execution.

API-compatible with the original SMACH (ros/executive_smach), strict where the
original silently lost data or hung, and fast. Pure Python, no ROS.
"""

from __future__ import annotations

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
from smach.log import logdebug, logerr, loginfo, logwarn, set_loggers
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
    is_shutdown,
    set_shutdown_check,
)
from smach.validation import ValidationReport, validate
from smach.wrapper import Wrapper

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
