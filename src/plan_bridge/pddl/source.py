"""PDDL source text: reading, structural pre-checks and error locations.

unified-planning parses PDDL with pyparsing. Given a file that is binary, huge,
unbalanced or nested thousands deep it produces a long traceback, a
``RecursionError`` or minutes of backtracking; given a construct it does not know
(``(either ...)`` types, derived predicates) it reports a generic
``Expected ')', found '('`` at the start of the surrounding form. So every file is
checked here first, with a cheap regular-expression tokenizer that knows line and
column of every token, and nothing reaches the parser that we can explain better
ourselves. None of this imports unified-planning, so bad input fails fast.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from plan_bridge.errors import PddlError
from plan_bridge.pddl.constructs import UP_REQUIREMENTS, check_constructs, did_you_mean
from plan_bridge.pddl.features import classify
from plan_bridge.pddl.source_text import SourceText

__all__ = [
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_DEPTH",
    "UP_REQUIREMENTS",
    "ProblemText",
    "SourceText",
    "check_source",
    "decode_source",
    "is_number",
    "read_source",
]

DEFAULT_MAX_BYTES = 5_000_000
DEFAULT_MAX_DEPTH = 200

#: What to write instead of a section that belongs to the other kind of file.
_MISPLACED_SECTION = {
    ":constants": "declare the problem's own objects in (:objects ...); "
    "constants shared by every problem go in the domain's (:constants ...)",
    ":objects": "declare objects every problem shares in the domain's (:constants ...), "
    "and the rest in each problem's (:objects ...)",
}

#: Section keywords of each kind of file (PDDL 1.2 to 3.1, PDDL+ and HTN).
_SECTIONS = {
    "domain": frozenset(
        [
            ":requirements",
            ":types",
            ":constants",
            ":predicates",
            ":functions",
            ":action",
            ":durative-action",
            ":derived",
            ":constraints",
            ":process",
            ":event",
            ":task",
            ":method",
            ":extends",
            ":timeless",
        ]
    ),
    "problem": frozenset(
        [
            ":domain",
            ":requirements",
            ":objects",
            ":init",
            ":goal",
            ":constraints",
            ":metric",
            ":htn",
            ":length",
            ":situation",
        ]
    ),
}

#: The keywords an action's definition may use.
_ACTION_KEYWORDS = {
    ":action": (":parameters", ":precondition", ":effect"),
    ":durative-action": (":parameters", ":duration", ":condition", ":effect"),
}


def read_source(path: str | Path, kind: str, *, max_bytes: int = DEFAULT_MAX_BYTES) -> SourceText:
    """Read a PDDL file, refusing what cannot be PDDL text.

    Raises :class:`PddlError` for a missing/unreadable file, a file larger than
    ``max_bytes``, binary content or text that is not UTF-8.
    """
    shown = str(path)
    file = Path(path)
    try:
        size = file.stat().st_size
    except FileNotFoundError as exc:
        raise PddlError(
            f"{kind} file not found", path=shown, hint=f"expected a PDDL {kind} file"
        ) from exc
    except OSError as exc:
        raise PddlError(f"cannot access {kind} file: {exc.strerror}", path=shown) from exc
    if file.is_dir():
        raise PddlError(f"is a directory, expected a PDDL {kind} file", path=shown)
    if size > max_bytes:
        raise PddlError(
            f"{kind} file is {size / 1e6:.1f} MB, larger than the {max_bytes / 1e6:.1f} MB limit",
            path=shown,
            hint="the limit guards against runaway or wrong files (a robot's PDDL is rarely over "
            "1 MB); from Python, load_task(..., max_bytes=N) reads a larger file",
        )
    try:
        data = file.read_bytes()
    except OSError as exc:
        raise PddlError(f"cannot read {kind} file: {exc.strerror}", path=shown) from exc
    return decode_source(data, shown, kind)


def decode_source(data: bytes, path: str, kind: str) -> SourceText:
    """Decode bytes as UTF-8 PDDL text (a BOM is allowed), refusing binary data."""
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        start = data.rfind(b"\n", 0, nul) + 1
        column = nul - start + 1
        end = data.find(b"\n", nul)
        row = data[start : end if end >= 0 else len(data)][:160]
        shown = row.decode("ascii", "replace").replace("\x00", "?")
        raise PddlError(
            f"binary data (a NUL byte) in the {kind} file: this is not a PDDL text file",
            path=path,
            line=line,
            column=column,
            excerpt=f"{shown}\n{' ' * (column - 1)}^" if column <= 160 else "",
        )
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise PddlError(
            f"the {kind} file is not UTF-8 text (invalid byte 0x{data[exc.start]:02x})",
            path=path,
            line=line,
            column=column,
            hint="PDDL files must be plain ASCII/UTF-8 text",
        ) from exc
    return SourceText(text, path, kind)


def check_source(
    source: SourceText,
    *,
    max_depth: int = DEFAULT_MAX_DEPTH,
    max_bytes: int = DEFAULT_MAX_BYTES,
) -> None:
    """Structural checks: bounded size, balanced parentheses, bounded nesting, right
    file kind, and the constructs unified-planning 1.3 cannot read."""
    if len(source.text) > max_bytes:
        raise source.error(
            f"the {source.kind} text is {len(source.text) / 1e6:.1f} MB, larger than the "
            f"{max_bytes / 1e6:.1f} MB limit",
            None,
            hint="raise the limit with max_bytes=... if this text is really meant to be loaded",
        )
    tokens = source.tokens
    if not tokens:
        raise source.error(
            f"the {source.kind} file is empty (only whitespace or comments)",
            None,
            hint=f"expected (define ({source.kind} NAME) ...)",
        )
    _check_parentheses(source, max_depth)
    _check_header(source)
    _check_keywords(source)
    check_constructs(source)


def _check_parentheses(source: SourceText, max_depth: int) -> None:
    open_offsets: list[int] = []
    tokens = source.tokens
    for index, token in enumerate(tokens):
        if token.text == "(":
            open_offsets.append(token.offset)
            if len(open_offsets) > max_depth:
                raise source.error(
                    f"parentheses nested deeper than {max_depth} levels",
                    token.offset,
                    hint="real PDDL is rarely nested more than 20 deep; is the file generated "
                    "wrongly?",
                )
        elif token.text == ")":
            if not open_offsets:
                raise source.error(
                    "unbalanced parentheses: this ')' has no matching '('",
                    token.offset,
                )
            open_offsets.pop()
            if not open_offsets and index + 1 < len(tokens):
                following = tokens[index + 1]
                if (
                    following.text == "("
                    and index + 2 < len(tokens)
                    and tokens[index + 2].text.startswith(":")
                    # Indented like a section inside (define ...): more likely one ')'
                    # too many before it, reported at that ')' below.
                    and source.line_col(following.offset)[1] == 1
                ):
                    line, column = source.line_col(token.offset)
                    raise source.error(
                        f"section ({tokens[index + 2].text} ...) after the end of the "
                        f"(define ...) form, which the ')' at {line}:{column} closes",
                        following.offset,
                        hint="is there one ')' too many before it? Sections belong inside "
                        "(define ...)",
                    )
                line, column = source.line_col(following.offset)
                raise source.error(
                    "unbalanced parentheses: this ')' closes the (define ...) form, but more "
                    f"text follows at {line}:{column}",
                    token.offset,
                    hint="is this an extra ')'? A PDDL file holds exactly one (define ...) form",
                )
    if open_offsets:
        suspect = _unclosed_by_indentation(source)
        if suspect is not None:
            unclosed, inside = suspect
            line, column = source.line_col(inside)
            raise source.error(
                "unbalanced parentheses: this '(' is never closed (the '(' at "
                f"{line}:{column}, indented like it, is still inside it)",
                unclosed,
                hint="is a ')' missing at the end of this form?",
            )
        innermost = open_offsets[-1]
        line, column = source.line_col(open_offsets[0])
        raise source.error(
            f"unbalanced parentheses: the file ends while {len(open_offsets)} '(' are still "
            f"open; the innermost unclosed '(' is here (the outermost opened at "
            f"{line}:{column})",
            innermost,
            hint="is the file truncated, or is a ')' missing?",
        )


def _unclosed_by_indentation(source: SourceText) -> tuple[int, int] | None:
    """When a ')' is missing, the form that lacks it is usually the one a later line,
    indented no deeper, still sits inside: (offset of its '(', offset of that line's '(')."""
    text = source.text
    stack: list[tuple[int, int, bool]] = []  # offset, column, first on its line
    for token in source.tokens:
        if token.text == "(":
            line_start = text.rfind("\n", 0, token.offset) + 1
            first = not text[line_start : token.offset].strip()
            column = token.offset - line_start
            if first:
                for offset, open_column, open_first in stack[1:]:
                    if open_first and open_column >= column:
                        return offset, token.offset
            stack.append((token.offset, column, first))
        elif token.text == ")" and stack:
            stack.pop()
    return None


def _check_header(source: SourceText) -> None:
    tokens = source.tokens
    other = "problem" if source.kind == "domain" else "domain"
    if len(tokens) < 4 or tokens[0].text != "(" or tokens[1].text != "define":
        first = tokens[1] if len(tokens) > 1 and tokens[0].text == "(" else tokens[0]
        raise source.error(
            f"expected (define ({source.kind} NAME) ...), found {first.text!r}",
            first.offset,
        )
    if tokens[2].text != "(" or tokens[3].text not in {"domain", "problem"}:
        raise source.error(
            f"expected ({source.kind} NAME) after 'define', found {tokens[3].text!r}",
            tokens[3].offset if tokens[2].text == "(" else tokens[2].offset,
        )
    if tokens[3].text == other:
        raise source.error(
            f"this is a PDDL {other} file, but a {source.kind} file was expected here",
            tokens[3].offset,
            hint="pass the domain file first and the problem file second",
        )


def _check_keywords(source: SourceText) -> None:
    """Section keywords, and the keywords of every action: a misspelt one gets its
    name, place and the allowed ones (unified-planning would say ``Expected ')'``)."""
    tokens = source.tokens
    allowed_sections = _SECTIONS[source.kind]
    depth = 0
    keywords: tuple[str, ...] = ()
    where = ""
    for index, token in enumerate(tokens):
        if token.text == "(":
            depth += 1
            if depth == 2 and index + 1 < len(tokens):
                head = tokens[index + 1]
                keywords = ()
                if head.text in {"domain", "problem"} and index == 2:
                    continue
                other = "problem" if source.kind == "domain" else "domain"
                if head.text not in allowed_sections and head.text in _SECTIONS[other]:
                    raise source.error(
                        f"{head.text} is a {other} section; a {source.kind} file cannot have it",
                        head.offset,
                        hint=_MISPLACED_SECTION.get(head.text, f"move it into the {other} file"),
                    )
                if head.text not in allowed_sections:
                    raise source.error(
                        f"unknown {source.kind} section {head.text!r}"
                        + did_you_mean(head.text, allowed_sections),
                        head.offset,
                        hint=f"a {source.kind} file has the sections "
                        + " ".join(sorted(allowed_sections)),
                    )
                if head.text in _ACTION_KEYWORDS and index + 2 < len(tokens):
                    keywords = _ACTION_KEYWORDS[head.text]
                    where = f"({head.text} {tokens[index + 2].text} ...)"
        elif token.text == ")":
            depth -= 1
        elif (
            depth == 2
            and keywords
            and token.text.startswith(":")
            and token.text not in keywords
            and classify(token.text) is None  # e.g. :observe: classified, not a typo
            and tokens[index - 1].text != "("  # the section's own keyword
        ):
            raise source.error(
                f"unknown keyword {token.text!r} in {where}" + did_you_mean(token.text, keywords),
                token.offset,
                hint=f"({where.split()[0][1:]} NAME ...) takes "
                + ", ".join(keywords[:-1])
                + f" and {keywords[-1]}",
            )


def is_number(text: str) -> bool:
    """Whether ``text`` reads as a number (``2``, ``-0.5``, ``1e3``)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class ProblemText:
    """The PDDL text of a base problem and the key workers cache its parse under.

    A problem built in memory (:class:`~plan_bridge.pddl.spec.ProblemSpec`) travels as
    its JSON data (``spec``) instead of problem text: the worker builds it with
    unified-planning's API, no PDDL reader involved.
    """

    domain: str
    problem: str
    key: str
    spec: str | None = None
    """The problem as JSON (``ProblemSpec.to_json``), in place of ``problem``."""

    def fields(self) -> dict[str, str]:
        """What a request to a worker carries of the base problem."""
        if self.spec is not None:
            return {"domain": self.domain, "spec": self.spec}
        return {"domain": self.domain, "problem": self.problem}

    @classmethod
    def of(cls, domain: str, problem: str) -> ProblemText:
        digest = hashlib.sha256()
        digest.update(domain.encode("utf-8"))
        digest.update(b"\0")
        digest.update(problem.encode("utf-8"))
        return cls(domain, problem, digest.hexdigest()[:32])
