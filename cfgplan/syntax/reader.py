"""Reading source text: Lark (LALR, positions on) plus a Transformer that maps
each grammar rule straight to an :class:`Sx` node or an IR object, its span
from the positions of its first and last tokens.

Entry points: :func:`read_domain` and :func:`read_state` (files or text).
Errors are :class:`~cfgplan.diagnostics.CfgplanError` with a span; syntax
errors are built from Lark's ``UnexpectedInput`` by :mod:`cfgplan.syntax.unexpected`.
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import os
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

import lark
from lark import Lark, Token
from lark.exceptions import UnexpectedInput
from lark.visitors import Transformer

from cfgplan.diagnostics import CfgplanError, error
from cfgplan.files import read_source
from cfgplan.ir.model import Domain, Functionality, Goal, Method, Span, State
from cfgplan.syntax import forms
from cfgplan.syntax.sx import Sx, token_end

T = TypeVar("T")

MAX_NESTING = 64
"""Lists may nest this deep; deeper input is refused (no recursion anywhere)."""


@cache
def grammar_text() -> str:
    """The grammar, read from the installed package data ``cfgplan.grammar``."""
    return resources.files("cfgplan.grammar").joinpath("cfgplan.lark").read_text("utf-8")


class GoalSequence(NamedTuple):
    """``(sequence G1 G2 ...)`` as read; it becomes :attr:`State.sequence` (a
    named tuple: a frozen dataclass takes four times as long to define)."""

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

    def add(self, items: Sequence[Any]) -> None:
        """File the forms the parser read, each under its kind, in file order."""
        for item in items:
            if isinstance(item, Functionality):
                self.functionalities.append(item)
            elif isinstance(item, Method):
                self.methods.append(item)
            elif isinstance(item, State):
                self.states.append(item)
            elif isinstance(item, Goal):
                self.goals.append(item)
            elif isinstance(item, GoalSequence):
                self.sequences.append(item.goals)


class _Run:
    """The children of an inlined rule, passed up to the rule that splices them in."""

    __slots__ = ("children",)

    def __init__(self, children: list[Any]) -> None:
        self.children = children


class _ToIR(Transformer[Token, Any]):
    """Maps grammar rules to Sx nodes (generic s-expressions) and IR objects.

    It runs inside the LALR parser (each rule as it is reduced: no parse tree
    is built, nothing recurses), so it takes no ``meta``: a form's or a list's
    span runs from its first token to its last, the parentheses the grammar
    keeps (``LPAR``, ``RPAR``). Lark calls every method named like a rule,
    an inlined ``_rule`` too: the helpers' names are none of the grammar's
    (:meth:`begin`, not ``start``, readies it for each file).

    A form or list found wrong is noted (:attr:`failed`, the first one) and the
    parse goes on: a syntax error anywhere in the file is reported before it,
    as when the whole tree was read first."""

    filename = "<text>"
    failed: CfgplanError | None = None

    def __default__(self, data: str, children: list[Any], meta: Any) -> _Run:
        """Every rule without a method of its own: ``start`` and the inlined
        ones (``_expr``, ``_quoted``, ``_form`` and the repetitions
        Lark makes of ``(...)*``), whose children the rule above splices
        into its own (Lark reads only their ``children``).

        Lark's default builds a ``Tree`` and, positions on, works out its
        start and end from its children's (two searches a rule); a
        :class:`_Run` carries the children alone. Safe: no span is taken
        from these nodes (spans come from the tokens, :meth:`_span`), and
        what the rule above receives, the children, is the same list."""
        return _Run(children)

    def _expr(self, children: list[Any]) -> _Run:
        """As :meth:`__default__`, called straight (Lark calls a method named
        like the rule, not through ``__default__``): the inlined rules reduced
        most often (a form's and a call's items; a list names its items'
        rules itself, grammar/cfgplan.lark)."""
        return _Run(children)

    _quoted = _form = _expr

    def begin(self, filename: str) -> None:
        self.filename, self.failed = filename, None

    def _fail(self, exc: CfgplanError) -> None:
        if self.failed is None:
            self.failed = exc

    def _build(self, build: Callable[[], T]) -> T | None:
        """``build()``, or None when it finds the form wrong (noted)."""
        try:
            return build()
        except CfgplanError as exc:
            self._fail(exc)
            return None

    def _span(self, first: Token, last: Token | Sx) -> Span:
        """From the start of the token ``first`` to the end of ``last``. The
        Span is made from the two positions directly (before, from a Span made
        for each token, two pydantic models thrown away a list): the same
        numbers, the same Span."""
        end_line, end_column = last.end if isinstance(last, Sx) else token_end(last)
        return Span(
            file=self.filename,
            line=first.line or 0,
            column=first.column or 0,
            end_line=end_line,
            end_column=end_column,
        )

    def _item(self, child: Any) -> Any:
        """A ``SYMBOL`` or ``NUMBER`` token as its node, anything else as it
        is. Symbols and numbers have no rule of their own (one reduction
        fewer each: chain D=100's domain is read in 3 % fewer instructions),
        so a rule that holds one makes it a node here."""
        if type(child) is Token:
            kind = child.type
            if kind == "SYMBOL":
                return Sx("symbol", text=str(child), at=child, file=self.filename)
            if kind == "NUMBER":
                return Sx("number", text=str(child), at=child, file=self.filename)
        return child

    def list(self, children: Sequence[Any]) -> Sx:
        item = self._item
        span = self._span(children[0], children[-1])
        return self._list(span, [item(c) for c in children[1:-1]])

    def _list(self, span: Span, items: Sequence[Any]) -> Sx:
        depth = 1 + max((i.depth for i in items), default=0)
        if depth > MAX_NESTING:
            self._fail(
                error(
                    f"lists nest more than {MAX_NESTING} levels deep here",
                    span,
                    "domains and states need only a few levels; check for a runaway '('",
                )
            )
            items = ()  # nothing deeper is kept: no check ever walks it
        return Sx("list", span, items=tuple(items), depth=depth)

    def quote(self, children: Sequence[Any]) -> Sx:
        quote_tok, value = children[0], self._item(children[1])
        head = Sx("symbol", text="quote", at=quote_tok, file=self.filename)
        return self._list(self._span(quote_tok, value), [head, value])

    def call(self, children: Sequence[Any]) -> Sx:
        name_tok, *args, _ = children
        head = Sx("symbol", text=str(name_tok), at=name_tok, file=self.filename)
        span = self._span(name_tok, children[-1])
        return self._list(span, [head, *(self._item(a) for a in args if a is not None)])

    def option(self, children: Sequence[Any]) -> forms.Option:
        keyword, *rest = children
        value = self._item(rest[-1])
        text = str(keyword)
        return forms.Option(text, Sx("symbol", text=text, at=keyword, file=self.filename), value)

    def functionality(self, children: Sequence[Any]) -> Functionality | None:
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.functionality(span, children[2:-1]))

    def method(self, children: Sequence[Any]) -> Method | None:
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.method(span, children[2:-1]))

    def state(self, children: Sequence[Any]) -> State | None:
        span = self._span(children[0], children[-1])
        items = [self._item(c) for c in children[2:-1]]
        return self._build(lambda: forms.state(span, items))

    def goal(self, children: Sequence[Any]) -> Goal | None:
        value = next(c for c in map(self._item, children[2:-1]) if isinstance(c, Sx))
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.goal(span, value))

    def sequence(self, children: Sequence[Any]) -> GoalSequence | None:
        span = self._span(children[0], children[-1])
        goals = [c for c in map(self._item, children[2:-1]) if isinstance(c, Sx)]
        return self._build(lambda: GoalSequence(tuple(forms.goal(c.span, c) for c in goals), span))


_lock = threading.Lock()


OPTIONS: dict[str, Any] = {
    "parser": "lalr",
    "propagate_positions": True,
    "maybe_placeholders": True,
}
"""Lark's options: LALR, positions on (every rule reduced knows where it was)."""


def cache_file() -> Path | None:
    """Where the analysed grammar is kept between runs (Lark's ``cache=``), or
    None when there is no folder to keep it in: ``cfgplan/`` in the user's
    cache folder (``$XDG_CACHE_HOME``, else ``~/.cache``). Lark reads it only
    when the hash it wrote inside matches the grammar, the options, Lark's and
    Python's versions; the name differs with the grammar, the options and the
    versions too, so that two cfgplans sharing the folder do not overwrite
    each other's.
    Building the LALR tables cost ``cfgplan plan`` about 30 ms of its 390;
    loading them takes 3 to 5. The file is Lark's pickle: it is kept where only
    its user writes (not Lark's default, the shared temporary folder, where
    another user could plant one)."""
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    if not os.path.isabs(home):  # as the XDG specification says: ignored
        return None
    key = f"{grammar_text()}{OPTIONS}{lark.__version__}{sys.version_info[:2]}".encode()
    return Path(home, "cfgplan", f"parser-{hashlib.sha256(key).hexdigest()[:16]}.lark")


def build_parser(cache: Path | None) -> tuple[Lark, _ToIR]:
    """A parser, its transformer inside (LALR only: faster than transforming
    a tree afterwards, and no tree is held), with :data:`OPTIONS`. With ``cache``,
    its tables are read from that file, or built and written there; a file
    that cannot be read (truncated, another Lark's) or written is ignored."""
    transformer = _ToIR()
    where: str | bool = False
    if cache is not None:
        with contextlib.suppress(OSError):
            cache.parent.mkdir(parents=True, exist_ok=True)
            where = str(cache)
    parser = Lark(grammar_text(), **OPTIONS, transformer=transformer, cache=where)
    return parser, transformer


@cache
def _parser() -> tuple[Lark, _ToIR]:
    """The parser every read uses (:func:`build_parser`, cached in :func:`cache_file`)."""
    return build_parser(cache_file())


@contextlib.contextmanager
def collection_paused() -> Iterator[None]:
    """Python's cycle collector off while a file is parsed, back on after
    (if it was on). A 150 KB domain makes some 300,000 objects, tokens, lists,
    Sx nodes, IR, most of them short-lived; every 700 allocations start a
    collection, and now and then one over the whole heap (all of cfgplan's
    and its libraries' objects): 12 % of the read of chain D=200 in a fresh
    ``cfgplan`` process (0.62 s -> 0.55 s). :func:`cfgplan.problem.load` keeps
    it off while the problem is checked and compiled too (chain D=200: 0.63 s
    -> 0.54 s for the whole load). Safe: nothing made or read changes (no
    finalizer of the reader's runs), only when cycles are freed, and the work
    is bounded by the input (a file is at most 4 MiB, :func:`read_text_file`)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


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
    parser, transformer = _parser()
    try:
        with _lock, collection_paused():  # one parser, its transformer told which file it reads
            transformer.begin(filename)
            items = parser.parse(text).children
            failed = transformer.failed
    except UnexpectedInput as exc:
        from cfgplan.syntax.unexpected import syntax_error  # for a wrong file only (issue 32)

        raise syntax_error(exc, filename, text) from None
    except RecursionError:  # pragma: no cover - the grammar and transformer are iterative
        raise error("input too deeply nested") from None
    if failed is not None:
        raise failed
    source.add(items)
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
