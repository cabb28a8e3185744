"""What a robot action of a pyrobosim world ends with, and how long the others take."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["ACTION_SECONDS", "ActionResult"]

#: Simulated seconds of the actions that are not drives (as in the domain).
ACTION_SECONDS = {
    "pick": 2.0,
    "place": 2.0,
    "open": 3.0,
    "close": 3.0,
    "detect": 1.0,
    "search": 1.0,
    "charge": 10.0,
}


@dataclass(frozen=True)
class ActionResult:
    """What a robot action ended with: pyrobosim's ``ExecutionStatus`` name and message."""

    status: str
    message: str = ""

    @property
    def outcome(self) -> str:
        """The skill outcome: ``succeeded``, ``preempted`` (CANCELED) or ``aborted``."""
        return {"SUCCESS": "succeeded", "CANCELED": "preempted"}.get(self.status, "aborted")

    @classmethod
    def of(cls, result: Any) -> ActionResult:
        return cls(str(result.status.name), str(result.message or ""))
