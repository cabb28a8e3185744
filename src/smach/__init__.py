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
from smach.iterator import Iterator
from smach.log import logdebug, logerr, loginfo, logwarn, set_loggers
from smach.sequence import Sequence
from smach.state import CBState, State
from smach.state_machine import StateMachine
from smach.user_data import Remapper, UserData
from smach.util import CBInterface, cb_interface, has_smach_interface, is_shutdown, set_shutdown_check

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
    "Sequence",
    "SmachError",
    "State",
    "StateMachine",
    "UserData",
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
    "state",
    "state_machine",
    "user_data",
    "util",
]
