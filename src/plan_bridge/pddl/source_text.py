"""The text of one PDDL file: its tokens, sections and positions (``file:line:column``).

:class:`SourceText` is what every check of the front end reads; the checks themselves
are in :mod:`~plan_bridge.pddl.source` and :mod:`~plan_bridge.pddl.constructs`, which
both import this module and not each other's back.
"""

from __future__ import annotations

import bisect
import contextlib
import gc
import re
from collections.abc import Iterator
from typing import NamedTuple

from plan_bridge.errors import PddlError, UnsupportedFeatureError

__all__ = ["SourceText", "Token", "paused_gc"]

#: A dash glued to the type after it (``?c -compressor``, as in some IPC files) is
#: two tokens, ``-`` and ``compressor``: no PDDL name starts with ``-``, and a
#: negative number has a digit after it.
_TOKEN = re.compile(r";[^\n]*|\(|\)|-(?=[^\W\d_])|[^\s();]+")


class Token(NamedTuple):
    """A word or parenthesis (lower case) and its character offset.

    A tuple, not a dataclass: a 10 MB file has millions of them."""

    text: str
    offset: int


@contextlib.contextmanager
def paused_gc() -> Iterator[None]:
    """Build millions of small objects (tokens, atoms) without the cyclic garbage
    collector rescanning them every few thousand allocations (3x faster on 10 MB)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


class SourceText:
    """The text of one PDDL file with position helpers.

    ``kind`` is ``"domain"`` or ``"problem"`` (what the file is expected to hold).
    """

    def __init__(self, text: str, path: str, kind: str) -> None:
        self.text = text
        self.path = path
        self.kind = kind
        self._line_starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self._tokens: list[Token] | None = None
        self._preamble: tuple[int, int] | None = None

    # -- positions -------------------------------------------------------------
    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a character offset."""
        index = bisect.bisect_right(self._line_starts, offset) - 1
        return index + 1, offset - self._line_starts[index] + 1

    def offset_of(self, line: int, column: int) -> int:
        line = max(1, min(line, len(self._line_starts)))
        return self._line_starts[line - 1] + max(column, 1) - 1

    def excerpt(self, line: int, column: int) -> str:
        """The source line and a caret under ``column`` (tabs kept for alignment)."""
        lines = self.text.splitlines()
        if not 1 <= line <= len(lines):
            return ""
        row = lines[line - 1]
        if len(row) > 160:
            start = max(0, column - 80)
            row = row[start : start + 160]
            column -= start
        marker = "".join("\t" if ch == "\t" else " " for ch in row[: column - 1]) + "^"
        return f"{row}\n{marker}"

    def error(
        self,
        explanation: str,
        offset: int | None,
        hint: str = "",
        *,
        feature: str | None = None,
        supporting_engines: tuple[str, ...] = (),
    ) -> PddlError:
        """A :class:`PddlError` (or :class:`UnsupportedFeatureError`) at ``offset``."""
        line = column = None
        excerpt = ""
        if offset is not None:
            line, column = self.line_col(offset)
            excerpt = self.excerpt(line, column)
        if feature is not None:
            return UnsupportedFeatureError(
                explanation,
                feature=feature,
                supporting_engines=supporting_engines,
                path=self.path,
                line=line,
                column=column,
                excerpt=excerpt,
                hint=hint,
            )
        return PddlError(
            explanation, path=self.path, line=line, column=column, excerpt=excerpt, hint=hint
        )

    # -- tokens ----------------------------------------------------------------
    @property
    def tokens(self) -> list[Token]:
        if self._tokens is None:
            with paused_gc():
                self._tokens = self._without_preamble(self._tokenize())
        return self._tokens

    @property
    def preamble(self) -> tuple[int, int] | None:
        """(start, end) of an ``(in-package ...)`` form before ``(define ...)``, which
        the tokens leave out (a Lisp preamble of early PDDL files, IPC 1998)."""
        _ = self.tokens
        return self._preamble

    def _without_preamble(self, tokens: list[Token]) -> list[Token]:
        if len(tokens) < 4 or tokens[0].text != "(" or tokens[1].text != "in-package":
            return tokens
        for index in range(2, min(len(tokens), 8)):
            if tokens[index].text == "(":
                return tokens
            if tokens[index].text == ")":
                if index + 1 == len(tokens):
                    return tokens
                self._preamble = (tokens[0].offset, tokens[index].offset + 1)
                return tokens[index + 1 :]
        return tokens

    def _tokenize(self) -> list[Token]:
        lowered = self.text.lower()
        if len(lowered) == len(self.text):
            return [Token(m[0], m.start()) for m in _TOKEN.finditer(lowered) if m[0][0] != ";"]
        # A few Unicode letters change length when lowered: lower word by word.
        return [
            Token(m[0].lower(), m.start()) for m in _TOKEN.finditer(self.text) if m[0][0] != ";"
        ]

    def sections(self) -> Iterator[tuple[str, int, int]]:
        """Top-level sections of the ``define`` form: (head, start, end) offsets.

        ``head`` is the section keyword plus, for actions, the action name
        (``":action lift"``); for the ``(domain x)`` / ``(problem x)`` header it is
        ``"domain"`` / ``"problem"``.
        """
        tokens = self.tokens
        depth = 0
        start = -1
        head = ""
        for index, token in enumerate(tokens):
            if token.text == "(":
                depth += 1
                if depth == 2:
                    start = token.offset
                    nxt = tokens[index + 1].text if index + 1 < len(tokens) else ""
                    head = nxt
                    if nxt in {":action", ":durative-action", ":derived"} and index + 2 < len(
                        tokens
                    ):
                        head = f"{nxt} {tokens[index + 2].text}"
            elif token.text == ")":
                if depth == 2:
                    yield head, start, token.offset + 1
                depth -= 1

    def section_at(self, offset: int) -> str | None:
        for head, start, end in self.sections():
            if start <= offset < end:
                return head
        return None
