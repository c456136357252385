"""The reader's shortcuts build what the long way builds (reading a
big domain faster, cfgplan/syntax/reader.py).

- Lark's inlined rules (``_expr``, ``_quoted``, the repetitions) are passed up
  as a bare list of children (``Run``), not a positioned ``Tree``: the IR is
  the one the same transformer makes of the tree Lark builds itself.
- A symbol's or number's span is made when asked for, from its token: every
  span the IR keeps covers the text it was read from, and an error at a
  symbol is placed on it.
- A list of atoms on one line is one token (the grammar's ``ATOMS``): the IR
  read, and every error's message and place, are those of the grammar
  without it (every list read token by token), on every file and on files
  broken at random.
- The curly quotes of text copied from the PDF are read as ``'`` before
  parsing (``reader.as_lexed``): every file, and every file with curly
  quotes put in at random, reads, or is refused with the same message at the
  same place, as by the grammar that named them in its terminals itself.
- The cycle collector is paused while a file is parsed, and restored.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from unittest import mock

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lark import Lark, Token
from pydantic import BaseModel

from benchmarks import families
from cfgplan.diagnostics import CfgplanError
from cfgplan.ir.model import Atom, Functionality, Method, Span
from cfgplan.syntax import reader
from cfgplan.syntax.sx import Sx
from cfgplan.syntax.transform import ToIR

ROOT = Path(__file__).resolve().parents[2]

GENERATED = [
    ("chain", (12,)),
    ("fusion", (4, 3, 4, 3)),
    ("wall", (3, 4, 3)),
    ("relay", (4, 4, 3)),
    ("ecology", (6, 2, 1)),
    ("media_tight", (4, 2, 1)),
    ("delegation", (3,)),
    ("gateway", (4,)),
    ("dag", (4,)),
    ("conversion", (5,)),
    ("deliveries", (3, 2)),
]
"""Generated domains and states, small: each family's forms once or more."""


def _texts() -> Iterator[tuple[str, str]]:
    """(name, text) of every file under domains/ and of generated ones."""
    for path in sorted((ROOT / "domains").rglob("*.lisp")):
        yield str(path.relative_to(ROOT)), path.read_text("utf-8")
    for name, args in GENERATED:
        domain, state = getattr(families, name)(*args)
        yield f"{name}{args}-domain", domain
        yield f"{name}{args}-state", state


TEXTS = list(_texts())


def _canon(value: Any) -> Any:
    """A value with every field, spans and fields-set included, and types."""
    if isinstance(value, BaseModel):
        fields = tuple((k, _canon(getattr(value, k))) for k in type(value).model_fields)
        return (type(value).__name__, fields, tuple(sorted(value.model_fields_set)))
    if isinstance(value, (tuple, list)):
        return (type(value).__name__, tuple(_canon(v) for v in value))
    return (type(value).__name__, value)


def _forms(source: reader.SourceFile) -> Any:
    return _canon(
        (source.functionalities, source.methods, source.states, source.goals, source.sequences)
    )


def _by_tree(text: str, filename: str) -> reader.SourceFile:
    """The long way: Lark builds its positioned tree (inlined rules spliced by
    Lark itself), then the reader's transformer maps it, afterwards."""
    parser = Lark(reader.grammar_text(), **reader.OPTIONS)
    transformer = ToIR()
    transformer.use(parser)
    transformer.begin(filename)
    items = transformer.transform(parser.parse(reader.as_lexed(reader.normalize(text)))).children
    assert transformer.failed == ()
    source = reader.SourceFile(filename, text)
    source.add(items)
    return source


@pytest.mark.parametrize(("name", "text"), TEXTS, ids=[n for n, _ in TEXTS])
def test_inside_the_parser_reads_as_a_tree_transformed(name: str, text: str) -> None:
    """The IR (spans, field sets, types) read inside the parser, inlined rules
    as bare lists, equals the IR of Lark's own tree transformed afterwards."""
    fast = reader.parse(text, name)
    assert fast.functionalities or fast.states  # something was read
    assert _forms(fast) == _forms(_by_tree(text, name))


def _token_by_token_grammar() -> str:
    """The reader's grammar without ``ATOMS``, as it was before the token was
    made: every list is read as "(", its items and ")"."""
    grammar = re.sub(r"^(ATOMS|_BLANK)\b.*\n", "", reader.grammar_text(), flags=re.MULTILINE)
    grammar = grammar.replace("     | ATOMS\n", "").replace("(list | ATOMS | ", "(list | ")
    rules = [line for line in grammar.split("\n") if not line.startswith("//")]
    assert not any("ATOMS" in line or "_BLANK" in line for line in rules)
    return grammar


@functools.cache
def _token_by_token() -> tuple[Lark, ToIR]:
    """A parser of :func:`_token_by_token_grammar` (its transformer, the reader's)."""
    return reader.build_parser(None, _token_by_token_grammar())


def _outcome(text: str, parser: tuple[Lark, ToIR] | None) -> Any:
    """What reading ``text`` gives: its forms, or each error's message, place and hint."""
    try:
        return ("read", _forms(reader.parse(text, "f.lisp", parser=parser)))
    except CfgplanError as exc:
        return ("refused", [(d.message, d.span, d.hint) for d in exc.diagnostics])


def _tokens(text: str) -> list[tuple[str, str]]:
    parser, _ = reader._parser()
    return [(t.type, str(t)) for t in parser.parse_interactive(text).iter_parse()]


def test_a_list_of_atoms_on_one_line_is_one_token() -> None:
    """Only a list of symbols and numbers on one line: not one nested, with
    a comma, or over two lines; nor a form, nor a call's arguments."""
    text = "(state (robot Pippi)\n (at Pippi\n R1) ((a 1.5) c), (d, e) robot(Emil) ( ))"
    assert _tokens(text) == [
        ("LPAR", "("), ("STATE", "state"), ("ATOMS", "(robot Pippi)"),
        ("LPAR", "("), ("SYMBOL", "at"), ("SYMBOL", "Pippi"), ("SYMBOL", "R1"), ("RPAR", ")"),
        ("LPAR", "("), ("ATOMS", "(a 1.5)"), ("SYMBOL", "c"), ("RPAR", ")"), ("COMMA", ","),
        ("LPAR", "("), ("SYMBOL", "d"), ("COMMA", ","), ("SYMBOL", "e"), ("RPAR", ")"),
        ("CALL_NAME", "robot"), ("LPAR", "("), ("SYMBOL", "Emil"), ("RPAR", ")"),
        ("ATOMS", "( )"), ("RPAR", ")"),
    ]  # fmt: skip


def _goal_list(grammar: str, text: str) -> Sx:
    """The list of ``(goal LIST)``, read by a tree of ``grammar`` transformed."""
    parser = Lark(grammar, **reader.OPTIONS)
    transformer = ToIR()
    transformer.use(parser)
    transformer.begin("g.lisp")
    value = parser.parse(text).children[0].children[2]
    found = transformer._leaf(value) if isinstance(value, Token) else transformer.transform(value)
    assert isinstance(found, Sx)
    return found


def test_the_atoms_of_a_one_line_list_are_the_nodes_read_one_by_one() -> None:
    """Symbols and numbers told apart as the lexer tells them (a number first:
    its priority is higher), each placed where it stands."""
    text = "(goal (a 1.5 b -2\t1.5x +3 ?v 7a))"
    fast = _goal_list(reader.grammar_text(), text)
    slow = _goal_list(_token_by_token_grammar(), text)
    assert [(i.kind, i.text, i.span) for i in fast.items] == [
        (i.kind, i.text, i.span) for i in slow.items
    ]
    kinds = "symbol number symbol number symbol number symbol symbol"
    assert [i.kind for i in fast.items] == kinds.split()
    assert (fast.span, fast.depth) == (slow.span, slow.depth)


EDGES = [
    "(goal a :k)",
    "(goal (a b) :k)",
    "(state a :k)",
    "(state (a b) 'c)",
    "(state (a b) (c d)",
    "(make-functionality (a b))",
    "(make-functionality :name '(f ?r) (a b))",
    "(state (grid" + " 0" * 12 + "\n 1))",
    "(state (grid" + " 0" * 12 + ", 1))",
    "(state (a\tb\f c) ( ) () (1.5x +3 -2))",
    "(state robot(Pippi) (in Pippi R1))",
    "(goal (f ?x) (g))",
    "(sequence (a b) '(c d), (e))",
]
"""Texts around a one-line list: keywords after a value, lists where none
may stand, a long list of numbers that goes on past its line, blanks."""


@pytest.mark.parametrize("text", EDGES)
def test_an_edge_reads_as_without_the_token(text: str) -> None:
    """Read, or refused with the same message, place and hint, as by the
    grammar without ``ATOMS``."""
    assert _outcome(text, None) == _outcome(text, _token_by_token())


def test_a_long_list_of_numbers_past_its_line_is_read_at_once() -> None:
    """A list of 60 numbers and a line break: the token does not match, and
    finding that out takes one try per atom (not two per number: 2^60 tries,
    as when an atom could be a NUMBER or a SYMBOL). A subprocess, so that a
    match that never ends fails the test instead of hanging the run."""
    code = (
        "from cfgplan.syntax.reader import parse\n"
        f"parse({'(state (grid' + ' 0' * 60 + chr(10) + ' 1))'!r}, 's.lisp')\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=30)


@pytest.mark.parametrize(("name", "text"), TEXTS, ids=[n for n, _ in TEXTS])
def test_one_line_lists_read_as_token_by_token(name: str, text: str) -> None:
    """Every file reads to the same IR, spans included, with ``ATOMS`` as without."""
    assert "ATOMS" in {kind for kind, _ in _tokens(reader.normalize(text))}
    assert _outcome(text, None) == _outcome(text, _token_by_token())


_BROKEN_BY = st.sampled_from(
    [*"()' ,;\n:a1?\t\"", "\x0b", "1.5", "(a b)", " (", ") ", " :k", " 0 1 2 3 4 5 6 7 8 9"]
)


@st.composite
def _broken(draw: st.DrawFn) -> str:
    """A bundled or generated file with a few characters deleted, inserted
    or copied from elsewhere in it."""
    text = list(draw(st.sampled_from([t for _, t in TEXTS])))
    for _ in range(draw(st.integers(1, 3))):
        at = draw(st.integers(0, len(text) - 1))
        how = draw(st.integers(0, 2))
        if how == 0:
            del text[at]
        elif how == 1:
            text.insert(at, draw(_BROKEN_BY))
        else:
            text.insert(at, text[draw(st.integers(0, len(text) - 1))])
    return "".join(text)


@pytest.mark.quick(37)
@settings(max_examples=3000, deadline=None, derandomize=True, database=None)
@given(_broken())
def test_a_broken_file_fails_alike_with_one_line_lists_as_tokens(text: str) -> None:
    """On a file broken at random the reader reads, or refuses it with the
    same message at the same place, with ``ATOMS`` as without (in the runs
    before this test: 3,710 of 5,850 such files refused, none differently)."""
    assert _outcome(text, None) == _outcome(text, _token_by_token())


def _naming_curly_quotes_grammar() -> str:
    """The reader's grammar as it was before the reader read curly quotes as
    ``'``: its quote and the classes of characters no token holds name
    ``’`` and ``‘`` themselves."""
    grammar = reader.grammar_text()
    assert grammar.count("()',;") == 5 and grammar.count('QUOTE: "\'"') == 1
    grammar = grammar.replace('QUOTE: "\'"', "QUOTE: /['’‘]/")
    return grammar.replace("()',;", "()'’‘,;")


@functools.cache
def _naming_curly_quotes() -> tuple[Lark, ToIR]:
    return reader.build_parser(None, _naming_curly_quotes_grammar())


def _outcome_naming_curly_quotes(text: str) -> Any:
    """What the reader gave before: the text parsed as it is (no
    ``as_lexed``), by :func:`_naming_curly_quotes_grammar`."""
    with mock.patch.object(reader, "as_lexed", lambda lexed: lexed):
        return _outcome(text, _naming_curly_quotes())


_CURLY = st.sampled_from(["’", "‘", "’(a b)", " ‘", "’ ", ";’", "\n‘"])


@st.composite
def _curly(draw: st.DrawFn) -> str:
    """A bundled or generated file with some of its quotes made curly and a
    few curly quotes put in anywhere (in a symbol, a keyword, a comment, a
    number, between forms)."""
    text = list(draw(st.sampled_from([t for _, t in TEXTS])))
    for at in [i for i, char in enumerate(text) if char == "'"]:
        text[at] = draw(st.sampled_from(["'", "’", "‘"]))
    for _ in range(draw(st.integers(0, 3))):
        text.insert(draw(st.integers(0, len(text))), draw(_CURLY))
    return "".join(text)


@pytest.mark.parametrize(("name", "text"), TEXTS, ids=[n for n, _ in TEXTS])
def test_curly_quotes_read_as_by_the_grammar_naming_them(name: str, text: str) -> None:
    """Every file, its quotes made curly, reads as by the grammar that named them."""
    curly = text.replace("'", "’")
    assert curly != text or "'" not in text
    assert _outcome(curly, None) == _outcome_naming_curly_quotes(curly)


@pytest.mark.quick(37)
@settings(max_examples=1000, deadline=None, derandomize=True, database=None)
@given(_curly())
def test_curly_quotes_anywhere_fail_alike_as_by_the_grammar_naming_them(text: str) -> None:
    """With curly quotes anywhere the reader reads, or refuses the file with
    the same message at the same place, as the grammar naming them did."""
    assert _outcome(text, None) == _outcome_naming_curly_quotes(text)


def _spans(value: Any) -> Iterator[tuple[BaseModel, Span]]:
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, BaseModel):
            span = getattr(item, "span", None)
            if isinstance(span, Span) and item is not span:
                yield item, span
            stack.extend(getattr(item, k) for k in type(item).model_fields if k != "span")
        elif isinstance(item, (tuple, list)):
            stack.extend(item)


def _slice(lines: list[str], span: Span) -> str:
    if span.line == span.end_line:
        return lines[span.line - 1][span.column - 1 : span.end_column - 1]
    first = lines[span.line - 1][span.column - 1 :]
    middle = lines[span.line : span.end_line - 1]
    return "\n".join([first, *middle, lines[span.end_line - 1][: span.end_column - 1]])


@pytest.mark.parametrize(("name", "text"), TEXTS, ids=[n for n, _ in TEXTS])
def test_every_span_covers_its_text(name: str, text: str) -> None:
    """Each node's span, cut out of the file, is the text it was read from:
    a form or an atom from its "(" (or its name, ``robot(Pippi)``) to its ")",
    holding the atom's name and arguments."""
    source = reader.parse(text, name)
    lines = reader.normalize(text).split("\n")
    seen = 0
    for node, span in _spans(_forms_of(source)):
        assert span.file == name
        cut = _slice(lines, span)
        assert cut.endswith(")"), (node, span, cut)
        assert cut[0] == "(" or cut[0].isalpha() or cut[0] in "'’‘", (node, span, cut)
        if isinstance(node, Atom):
            assert node.predicate in cut and all(a in cut for a in node.args), (node, cut)
        if isinstance(node, (Functionality, Method)):
            assert cut.startswith("(make-"), cut
        seen += 1
    assert seen


def _forms_of(source: reader.SourceFile) -> list[Any]:
    return [source.functionalities, source.methods, source.states, source.goals, source.sequences]


def test_an_error_at_a_symbol_is_placed_on_it() -> None:
    """A symbol's span, made only when an error asks for it, is its token's."""
    text = "(make-functionality :name '(f ?r)\n   :cost  abc)"
    with pytest.raises(CfgplanError) as caught:
        reader.parse(text, "x.lisp")
    span = caught.value.diagnostics[0].span
    assert span is not None
    assert (span.file, span.line, span.column, span.end_line, span.end_column) == (
        "x.lisp",
        2,
        11,
        2,
        14,  # "abc": columns 11 to 13, the end just past it
    )
    assert "found abc" in str(caught.value)


@pytest.mark.parametrize("gap", [" ", "\n   "])
def test_an_error_at_an_atom_of_a_list_is_placed_on_it(gap: str) -> None:
    """An atom of a list on one line (one ``ATOMS`` token, its atoms placed
    by the transformer) and of a list over two lines (read token by token):
    the error is on the atom, ``?r`` in ``(not ?r)``."""
    text = f"(make-functionality :name '(f ?r) :out '((x ?r))\n :postcond '((not{gap}?r)))"
    with pytest.raises(CfgplanError) as caught:
        reader.parse(text, "a.lisp")
    span = caught.value.diagnostics[0].span
    assert span is not None
    line = text.count("\n", 0, text.rindex("?r")) + 1
    column = text.rindex("?r") - text.rfind("\n", 0, text.rindex("?r"))
    assert (span.line, span.column, span.end_line, span.end_column) == (
        line,
        column,
        line,
        column + 2,
    )
    assert str(caught.value) == "expected an atom such as (camera ?r), found ?r"


def test_an_error_at_a_keyword_is_placed_on_it() -> None:
    """A keyword's span, made only when an error asks for it, is its token's."""
    text = "(make-functionality :name '(f ?r)\n :Cost 3)"
    with pytest.raises(CfgplanError) as caught:
        reader.parse(text, "k.lisp")
    span = caught.value.diagnostics[0].span
    assert span is not None
    assert (span.line, span.column, span.end_line, span.end_column) == (2, 2, 2, 7)
    assert str(caught.value) == "unknown keyword :Cost in make-functionality"


@pytest.mark.parametrize("enabled", [True, False])
@pytest.mark.parametrize("text", ["(state (robot Pippi))", "(state (robot Pippi)"])
def test_the_collector_is_restored(enabled: bool, text: str) -> None:
    """The cycle collector is as it was after a read, a failed one too."""
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        with contextlib.suppress(CfgplanError):  # the second text is cut short
            reader.parse(text, "s.lisp")
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()


def test_reading_a_file_pauses_the_collector(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """While the parser runs, the collector is off (the point of the pause)."""
    seen: list[bool] = []
    _, transformer = reader._parser()
    real = transformer.begin

    def begin(filename: str) -> None:
        seen.append(gc.isenabled())
        real(filename)

    monkeypatch.setattr(transformer, "begin", begin)
    path = tmp_path / "s.lisp"
    path.write_text("(state (robot Pippi))")
    reader.read_state(path)
    assert seen == [False]


@pytest.mark.parametrize("enabled", [True, False])
def test_loading_a_problem_pauses_the_collector_until_it_is_compiled(
    enabled: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """cfgplan.problem.load keeps the collector off while it checks and
    compiles what it read, not only while the parser runs, and leaves it as
    it was, after a refused problem too."""
    import cfgplan.problem as problem

    seen: list[bool] = []
    real = problem.compile_task

    def compiling(*args: Any, **kwargs: Any) -> Any:
        seen.append(gc.isenabled())
        return real(*args, **kwargs)

    monkeypatch.setattr(problem, "compile_task", compiling)
    cross = ROOT / "domains" / "cross-door"
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        loaded = problem.load(cross / "domain.lisp", cross / "state-6.2.2-step1.lisp")
        assert gc.isenabled() is enabled
        with pytest.raises(CfgplanError):
            problem.load(cross / "domain.lisp", cross / "state-6.2.2-step1.lisp", "(no-such R)")
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()
    assert seen == [False] and loaded.task is not None
