"""Findings of the PDDL front end: errors and warnings, each at a ``file:line:column``.

A :class:`Diagnostic` keeps the source and offset it is about and renders like a
compiler message (location, excerpt with a caret, what would be allowed). Checks add
them to a :class:`Diagnostics` collection; the front end raises the errors as one
:class:`~plan_bridge.errors.PddlError` and hands the warnings to the task.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from plan_bridge.errors import PddlError
from plan_bridge.pddl.source import SourceText

__all__ = ["Diagnostic", "Diagnostics"]


@dataclass(frozen=True)
class Diagnostic:
    """One finding. ``feature`` is set for an unsupported PDDL feature."""

    severity: str
    """``"error"`` or ``"warning"``."""
    source: SourceText
    offset: int | None
    explanation: str
    hint: str = ""
    feature: str | None = None
    supporting_engines: tuple[str, ...] = ()

    @property
    def location(self) -> str:
        if self.offset is None:
            return self.source.path
        line, column = self.source.line_col(self.offset)
        return f"{self.source.path}:{line}:{column}"

    @property
    def line(self) -> int | None:
        return None if self.offset is None else self.source.line_col(self.offset)[0]

    def to_error(self) -> PddlError:
        return self.source.error(
            self.explanation,
            self.offset,
            self.hint,
            feature=self.feature,
            supporting_engines=self.supporting_engines,
        )

    def __str__(self) -> str:
        text = str(self.to_error())
        return text if self.severity == "error" else text.replace(": ", ": warning: ", 1)


@dataclass
class Diagnostics:
    """The findings of one front-end pass, in the order they were found."""

    items: list[Diagnostic] = field(default_factory=list)

    def error(
        self,
        source: SourceText,
        offset: int | None,
        explanation: str,
        hint: str = "",
        *,
        feature: str | None = None,
        supporting_engines: tuple[str, ...] = (),
    ) -> None:
        self.items.append(
            Diagnostic("error", source, offset, explanation, hint, feature, supporting_engines)
        )

    def warning(
        self, source: SourceText, offset: int | None, explanation: str, hint: str = ""
    ) -> None:
        self.items.append(Diagnostic("warning", source, offset, explanation, hint))

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity == "error"]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity == "warning"]

    def raise_errors(self) -> None:
        """Raise the first error, with every further one listed in its hint."""
        errors = sorted(
            self.errors,
            key=lambda d: (d.source.kind != "domain", d.offset if d.offset is not None else -1),
        )
        if not errors:
            return
        first = errors[0]
        hint = first.hint
        if len(errors) > 1:
            more = "\n".join(f"  {d.location}: {d.explanation}" for d in errors[1:21])
            extra = f"\n  ... and {len(errors) - 21} more" if len(errors) > 21 else ""
            hint = (hint + "\n" if hint else "") + (
                f"{len(errors) - 1} more problem(s):\n{more}{extra}"
            )
        raise first.source.error(
            first.explanation,
            first.offset,
            hint,
            feature=first.feature,
            supporting_engines=first.supporting_engines,
        )
