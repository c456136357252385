"""Reading source text: Lark (LALR, positions on), the transformer of
:mod:`cfgplan.syntax.transform` inside the parser, and the files' forms filed
by kind (:class:`SourceFile`).

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
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import lark
from lark import Lark
from lark.exceptions import UnexpectedInput

from cfgplan.diagnostics import CfgplanError, error
from cfgplan.files import read_source
from cfgplan.ir.model import Domain, Functionality, Goal, Method, Span, State
from cfgplan.syntax.transform import GoalSequence, ToIR


@cache
def grammar_text() -> str:
    """The grammar, read from the installed package data ``cfgplan.grammar``."""
    return resources.files("cfgplan.grammar").joinpath("cfgplan.lark").read_text("utf-8")


@dataclass
class FormErrors(CfgplanError):
    """Forms of a file that are wrong: every one of them (``diagnostics``, in
    file order), with what the file holds besides (``source``: the forms that
    read) and the names the wrong ones declare (``unread``), so that ``cfgplan
    check`` can check the rest and report every problem at once."""

    source: SourceFile | None = None
    unread: tuple[str, ...] = ()


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


def build_parser(cache: Path | None, grammar: str | None = None) -> tuple[Lark, ToIR]:
    """A parser, its transformer inside (LALR only: faster than transforming
    a tree afterwards, and no tree is held), with :data:`OPTIONS`. With ``cache``,
    its tables are read from that file, or built and written there; a file
    that cannot be read (truncated, another Lark's) or written is ignored.
    ``grammar``: another grammar's text than :func:`grammar_text` (tests
    compare grammars; Lark reads a cache only if made from the same text)."""
    transformer = ToIR()
    where: str | bool = False
    if cache is not None:
        with contextlib.suppress(OSError):
            cache.parent.mkdir(parents=True, exist_ok=True)
            where = str(cache)
    parser = Lark(grammar or grammar_text(), **OPTIONS, transformer=transformer, cache=where)
    transformer.use(parser)
    return parser, transformer


@cache
def _parser() -> tuple[Lark, ToIR]:
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


def as_lexed(text: str) -> str:
    """What the parser reads of a normalized ``text``: the curly quotes ``’``
    and ``‘`` of text copied from the PDF as ``'``, one character for another,
    so that every position is the text's. Outside a comment (where any
    character is read alike) a curly quote can only be a quote, as ``'`` is:
    the grammar excludes all three from every other token, so the tokens and
    their places are the same, and the grammar names only ``'``. That keeps
    the lexer's character classes within Latin-1, which Python compiles
    quickly: a class holding a character past it (and more than two runs)
    is compiled into a table of all 65,536 characters, about 0.1 ms each
    time, and the contextual lexer compiles such classes for every set of
    terminals it meets (10 ms of ``cfgplan plan`` on cross-door)."""
    return text.replace("’", "'").replace("‘", "'")


def decode(data: bytes, filename: str, *, quoting: bool = False) -> str:
    """Decode UTF-8 source (see :func:`normalize`); a bad byte is reported at
    its line and column. ``quoting``: the text to quote in a message about the
    file, a bad byte shown as U+FFFD (one character, so columns still match)."""
    data = data.removeprefix(BOM.encode("utf-8")).replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if quoting:
        return data.decode("utf-8", errors="replace")
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


def parse(
    text: str, filename: str = "<text>", *, parser: tuple[Lark, ToIR] | None = None
) -> SourceFile:
    """Parse one file's text into its forms (functionalities, methods, states, goals).

    The text is normalized first (:func:`normalize`); spans count lines in the
    result. The parser reads it :func:`as_lexed`; messages quote it as written.
    ``parser``: another parser and its transformer (:func:`build_parser`), not
    the one every read uses (tests compare grammars)."""
    text = normalize(text)
    source = SourceFile(filename, text)
    if not text.strip() or all(
        not ln.strip() or ln.lstrip().startswith(";") for ln in text.split("\n")
    ):
        span = Span(file=filename, line=1, column=1, end_line=1, end_column=1)
        raise error("the file is empty: it holds no forms", span)
    lark_parser, transformer = parser or _parser()
    try:
        with _lock, collection_paused():  # one parser, its transformer told which file it reads
            transformer.begin(filename)
            items = lark_parser.parse(as_lexed(text)).children
            failed = transformer.failed
    except UnexpectedInput as exc:
        from cfgplan.syntax.unexpected import syntax_error  # for a wrong file only

        raise syntax_error(exc, filename, text) from None
    except RecursionError:  # pragma: no cover - the grammar and transformer are iterative
        raise error("input too deeply nested") from None
    source.add(items)
    if failed:
        raise FormErrors([d for exc in failed for d in exc.diagnostics], source, transformer.unread)
    return source


def read_text_file(path: str | Path) -> tuple[str, str]:
    """Read a regular file of at most 4 MiB as UTF-8 (:func:`cfgplan.files.read_source`);
    returns (display name, normalized text)."""
    name = str(path)
    return name, decode(read_source(path), name)


def domain_from(source: SourceFile) -> Domain:
    """A Domain from a parsed file; state and goal forms do not belong there."""
    for item in (*source.states, *source.goals, *(s[0] for s in source.sequences)):
        swapped = not source.functionalities and not source.methods
        raise error(
            "a domain file holds only make-functionality and make-config-method forms",
            item.span,
            "the domain file comes first, then the state file (DOMAIN STATE)"
            if swapped
            else "put (state ...) and (goal ...) in the state file",
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
