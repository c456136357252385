"""Reading source text: Lark (LALR, positions on) plus a Transformer that maps
each grammar rule straight to an :class:`Sx` node or an IR object.

Entry points: :func:`read_domain` and :func:`read_state` (files or text).
Errors are :class:`~cfgplan.diagnostics.CfgplanError` with a span; syntax
errors are built from Lark's ``UnexpectedInput`` by :mod:`cfgplan.syntax.unexpected`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from lark import Lark, Token, v_args
from lark.exceptions import UnexpectedInput, VisitError
from lark.visitors import Transformer_NonRecursive

from cfgplan.diagnostics import CfgplanError, error
from cfgplan.files import read_source
from cfgplan.ir.model import Domain, Functionality, Goal, Method, Span, State
from cfgplan.syntax import forms
from cfgplan.syntax.sx import Sx
from cfgplan.syntax.unexpected import syntax_error

MAX_NESTING = 64
"""Lists may nest this deep; deeper input is refused (no recursion anywhere)."""

@cache
def grammar_text() -> str:
    """The grammar, read from the installed package data ``cfgplan.grammar``."""
    return resources.files("cfgplan.grammar").joinpath("cfgplan.lark").read_text("utf-8")


@dataclass(frozen=True)
class GoalSequence:
    """``(sequence G1 G2 ...)`` as read; it becomes :attr:`State.sequence`."""

    goals: tuple[Goal, ...]
    span: Span


@dataclass
class SourceFile:
    """Everything one file declares, in file order."""

    name: str
    text: str
    functionalities: list[Functionality] = field(default_factory=list)
    methods: list[Method] = field(default_factory=list)
    states: list[State] = field(default_factory=list)
    goals: list[Goal] = field(default_factory=list)
    sequences: list[tuple[Goal, ...]] = field(default_factory=list)


class _ToIR(Transformer_NonRecursive[Token, Any]):
    """Maps grammar rules to Sx nodes (generic s-expressions) and IR objects."""

    def __init__(self, filename: str) -> None:
        super().__init__(visit_tokens=False)
        self.filename = filename

    def _span(self, meta: Any) -> Span:
        return Span(
            file=self.filename,
            line=meta.line,
            column=meta.column,
            end_line=meta.end_line,
            end_column=meta.end_column,
        )

    def _token_span(self, tok: Token) -> Span:
        return Span(
            file=self.filename,
            line=tok.line or 0,
            column=tok.column or 0,
            end_line=tok.end_line or tok.line or 0,
            end_column=tok.end_column or tok.column or 0,
        )

    @v_args(inline=True)
    def symbol(self, tok: Token) -> Sx:
        return Sx("symbol", self._token_span(tok), text=str(tok))

    @v_args(inline=True)
    def number(self, tok: Token) -> Sx:
        return Sx("number", self._token_span(tok), text=str(tok))

    @v_args(meta=True)
    def list(self, meta: Any, children: Sequence[Any]) -> Sx:
        return self._list(self._span(meta), children)

    def _list(self, span: Span, items: Sequence[Any]) -> Sx:
        depth = 1 + max((i.depth for i in items), default=0)
        if depth > MAX_NESTING:
            raise error(
                f"lists nest more than {MAX_NESTING} levels deep here",
                span,
                "domains and states need only a few levels; check for a runaway '('",
            )
        return Sx("list", span, items=tuple(items), depth=depth)

    @v_args(meta=True)
    def quote(self, meta: Any, children: Sequence[Any]) -> Sx:
        quote_tok, value = children
        span = self._span(meta)
        head = Sx("symbol", self._token_span(quote_tok), text="quote")
        return self._list(span, [head, value])

    @v_args(meta=True)
    def call(self, meta: Any, children: Sequence[Any]) -> Sx:
        name_tok, *args = children
        head = Sx("symbol", self._token_span(name_tok), text=str(name_tok))
        return self._list(self._span(meta), [head, *(a for a in args if a is not None)])

    @v_args(meta=True)
    def option(self, meta: Any, children: Sequence[Any]) -> forms.Option:
        keyword, *rest = children
        value = rest[-1]
        return forms.Option(str(keyword), self._token_span(keyword), value)

    @v_args(meta=True)
    def functionality(self, meta: Any, children: Sequence[Any]) -> Functionality:
        return forms.functionality(self._span(meta), children[1:])

    @v_args(meta=True)
    def method(self, meta: Any, children: Sequence[Any]) -> Method:
        return forms.method(self._span(meta), children[1:])

    @v_args(meta=True)
    def state(self, meta: Any, children: Sequence[Any]) -> State:
        return forms.state(self._span(meta), children[1:])

    @v_args(meta=True)
    def goal(self, meta: Any, children: Sequence[Any]) -> Goal:
        value = next(c for c in children[1:] if isinstance(c, Sx))
        return forms.goal(self._span(meta), value)

    @v_args(meta=True)
    def sequence(self, meta: Any, children: Sequence[Any]) -> GoalSequence:
        span = self._span(meta)
        return GoalSequence(
            tuple(forms.goal(c.span, c) for c in children[1:] if isinstance(c, Sx)), span
        )


@cache
def _parser() -> Lark:
    return Lark(grammar_text(), parser="lalr", propagate_positions=True, maybe_placeholders=True)


BOM = "\ufeff"
"""The UTF-8 byte-order mark some editors put first; it is skipped."""


def normalize(text: str) -> str:
    """``text`` without a leading byte-order mark, every line break (``\r\n``, or
    a ``\r`` alone as old Mac editors write) made a ``\n``: line breaks are
    white space to the language, and so lines are counted alike everywhere."""
    return text.removeprefix(BOM).replace("\r\n", "\n").replace("\r", "\n")


def decode(data: bytes, filename: str) -> str:
    """Decode UTF-8 source (see :func:`normalize`); a bad byte is reported at
    its line and column."""
    data = data.removeprefix(BOM.encode("utf-8")).replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start]
        line = before.count(b"\n") + 1
        # Count characters, not bytes: what precedes the bad byte decodes cleanly.
        line_start = before.rfind(b"\n") + 1
        column = len(data[line_start : exc.start].decode("utf-8")) + 1
        span = Span(file=filename, line=line, column=column, end_line=line, end_column=column + 1)
        raise error(
            f"invalid UTF-8 byte 0x{data[exc.start]:02x}",
            span,
            "cfgplan reads UTF-8 text; re-save the file as UTF-8",
        ) from None


def parse(text: str, filename: str = "<text>") -> SourceFile:
    """Parse one file's text into its forms (functionalities, methods, states, goals).

    The text is normalized first (:func:`normalize`); spans count lines in the result."""
    text = normalize(text)
    source = SourceFile(filename, text)
    if not text.strip() or all(
        not ln.strip() or ln.lstrip().startswith(";") for ln in text.split("\n")
    ):
        span = Span(file=filename, line=1, column=1, end_line=1, end_column=1)
        raise error("the file is empty: it holds no forms", span)
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as exc:
        raise syntax_error(exc, filename, text) from None
    except RecursionError:  # pragma: no cover - the grammar and transformer are iterative
        raise error("input too deeply nested") from None
    try:
        items = _ToIR(filename).transform(tree).children
    except VisitError as exc:
        if isinstance(exc.orig_exc, CfgplanError):
            raise exc.orig_exc from None
        raise
    for item in items:
        if isinstance(item, Functionality):
            source.functionalities.append(item)
        elif isinstance(item, Method):
            source.methods.append(item)
        elif isinstance(item, State):
            source.states.append(item)
        elif isinstance(item, Goal):
            source.goals.append(item)
        elif isinstance(item, GoalSequence):
            source.sequences.append(item.goals)
    return source


def read_text_file(path: str | Path) -> tuple[str, str]:
    """Read a regular file of at most 4 MiB as UTF-8 (:func:`cfgplan.files.read_source`);
    returns (display name, normalized text)."""
    name = str(path)
    return name, decode(read_source(path), name)


def domain_from(source: SourceFile) -> Domain:
    """A Domain from a parsed file; state and goal forms do not belong there."""
    for item in (*source.states, *source.goals, *(s[0] for s in source.sequences)):
        raise error(
            "a domain file holds only make-functionality and make-config-method forms",
            item.span,
            "put (state ...) and (goal ...) in the state file",
        )
    span = Span(file=source.name, line=1, column=1, end_line=1, end_column=1)
    return Domain(
        functionalities=tuple(source.functionalities), methods=tuple(source.methods), span=span
    )


def state_from(source: SourceFile) -> State:
    """The State of a parsed state file, with its goal if one is given."""
    for item in (*source.functionalities, *source.methods):
        raise error(
            "a state file holds one (state ...) form and an optional (goal ...)",
            item.span,
            "put make-functionality and make-config-method forms in the domain file",
        )
    if not source.states:
        span = Span(file=source.name, line=1, column=1, end_line=1, end_column=1)
        raise error("no (state ...) form in this file", span)
    if len(source.states) > 1:
        raise error("a second (state ...) form; a state file holds one", source.states[1].span)
    if len(source.goals) > 1:
        raise error("a second (goal ...) form; a state file holds one", source.goals[1].span)
    if source.sequences and (source.goals or len(source.sequences) > 1):
        where = source.sequences[-1][0].span
        raise error(
            "a state file holds one (goal ...) or one (sequence ...), not both",
            where,
            "write every goal, in order, in one (sequence G1 G2 ...)",
        )
    state = source.states[0]
    if source.goals:
        state = state.model_copy(update={"goal": source.goals[0]})
    if source.sequences:
        state = state.model_copy(update={"sequence": source.sequences[0]})
    return state


def read_domain(path: str | Path) -> tuple[Domain, str]:
    """Parse a domain file; returns the Domain and the file's text (for messages)."""
    name, text = read_text_file(path)
    return domain_from(parse(text, name)), text


def read_state(path: str | Path) -> tuple[State, str]:
    """Parse a state file; returns the State and the file's text."""
    name, text = read_text_file(path)
    return state_from(parse(text, name)), text
