"""Logging hooks of smach.

The four functions ``loginfo``, ``logwarn``, ``logdebug`` and ``logerr`` are module
attributes of :mod:`smach`; library code looks them up there at call time, so
``smach.set_loggers(...)`` (or plain assignment) takes effect everywhere at once.
By default they forward to the Python logger named ``"smach"``.

Messages about normal execution (transitions, starts, terminations) are produced by a
listener of the event stream, and only when someone would see them: when custom
loggers are installed, or when the ``smach`` logger is enabled for INFO.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from typing import Any

__all__ = ["logdebug", "logerr", "loginfo", "logwarn", "set_loggers"]

LogFunction = Callable[[Any], Any]

_logger = logging.getLogger("smach")


def loginfo(msg: Any) -> None:
    """Log at INFO through the ``smach`` Python logger."""
    _logger.info("%s", msg)


def logwarn(msg: Any) -> None:
    """Log at WARNING through the ``smach`` Python logger."""
    _logger.warning("%s", msg)


def logdebug(msg: Any) -> None:
    """Log at DEBUG through the ``smach`` Python logger."""
    _logger.debug("%s", msg)


def logerr(msg: Any) -> None:
    """Log at ERROR through the ``smach`` Python logger."""
    _logger.error("%s", msg)


_DEFAULTS = {"loginfo": loginfo, "logwarn": logwarn, "logdebug": logdebug, "logerr": logerr}


def set_loggers(
    info: LogFunction, warn: LogFunction, debug: LogFunction, error: LogFunction
) -> None:
    """Replace the four loggers of smach (argument order as in the original SMACH)."""
    smach = sys.modules["smach"]
    for name, fn in (("loginfo", info), ("logwarn", warn), ("logdebug", debug), ("logerr", error)):
        setattr(smach, name, fn)


def info_enabled() -> bool:
    """Whether INFO messages would reach anybody (checked once per container run)."""
    smach = sys.modules["smach"]
    if smach.loginfo is not loginfo:
        return True
    return _logger.isEnabledFor(logging.INFO)


def debug_enabled() -> bool:
    """Whether DEBUG messages would reach anybody."""
    smach = sys.modules["smach"]
    if smach.logdebug is not logdebug:
        return True
    return _logger.isEnabledFor(logging.DEBUG)


def restore_default_loggers() -> None:
    """Put the default (Python ``logging``) loggers back."""
    smach = sys.modules["smach"]
    for name, fn in _DEFAULTS.items():
        setattr(smach, name, fn)
