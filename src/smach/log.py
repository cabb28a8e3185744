"""Logging hooks of smach.

The four loggers ``loginfo``, ``logwarn``, ``logdebug`` and ``logerr`` that smach
calls are held by :data:`loggers`; library code looks them up there at call time
(``loggers.logwarn(...)``). ``smach.loginfo`` and the three others are views of it
(the ``smach`` module's type makes them so), so ``smach.set_loggers(...)`` or plain
assignment (``smach.loginfo = f``, as in the original) takes effect everywhere at
once, and no module of smach imports the ``smach`` package for them. By default
they forward to the Python logger named ``"smach"`` (the functions of this module).

Messages about normal execution (transitions, starts, terminations) are produced by a
listener of the event stream, and only when someone would see them: when custom
loggers are installed, or when the ``smach`` logger is enabled for INFO.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

__all__ = ["Loggers", "logdebug", "logerr", "loggers", "loginfo", "logwarn", "set_loggers"]

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


class Loggers:
    """The four loggers smach calls now (``smach.loginfo`` and the others read and set
    these attributes)."""

    __slots__ = ("logdebug", "logerr", "loginfo", "logwarn")

    def __init__(self) -> None:
        self.loginfo: LogFunction = loginfo
        self.logwarn: LogFunction = logwarn
        self.logdebug: LogFunction = logdebug
        self.logerr: LogFunction = logerr


#: The loggers of this process.
loggers = Loggers()


def set_loggers(
    info: LogFunction, warn: LogFunction, debug: LogFunction, error: LogFunction
) -> None:
    """Replace the four loggers of smach (argument order as in the original SMACH)."""
    loggers.loginfo, loggers.logwarn, loggers.logdebug, loggers.logerr = info, warn, debug, error


def info_enabled() -> bool:
    """Whether INFO messages would reach anybody (checked once per top-level run).

    True for custom loggers, unless the installed ``loginfo`` is the ``info`` method
    of a logger that can say it drops INFO: a Python :class:`logging.Logger` (or
    ``LoggerAdapter``) not enabled for INFO, or a logger with
    ``get_effective_level()`` above INFO (an rclpy/rcutils logger, whose INFO is 20
    too). Then no container formats a line that would be dropped.
    """
    info = loggers.loginfo
    if info is loginfo:
        return _logger.isEnabledFor(logging.INFO)
    return _drops_info(info) is not True


def _drops_info(info: Any) -> bool | None:
    """Whether the logger method ``info`` drops INFO messages (None: cannot tell)."""
    owner = getattr(info, "__self__", None)
    if owner is None or getattr(info, "__name__", "") != "info":
        return None
    try:
        if isinstance(owner, logging.Logger | logging.LoggerAdapter):
            return not owner.isEnabledFor(logging.INFO)
        level = getattr(owner, "get_effective_level", None)
        if callable(level):
            return bool(int(level()) > logging.INFO)
    except Exception:  # a logger that cannot answer: assume it writes
        return None
    return None


def restore_default_loggers() -> None:
    """Put the default (Python ``logging``) loggers back."""
    set_loggers(loginfo, logwarn, logdebug, logerr)
