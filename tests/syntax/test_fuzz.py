"""Fuzzing the front end: random and mutated text never gives a traceback.

Property, for any input text: reading it (``parse`` then ``domain_from`` or
``state_from``) and checking what was read either succeeds or raises a
:class:`CfgplanError` whose diagnostics each carry a message and a span with
line >= 1 and column >= 1. Nothing else escapes, and nothing hangs (deadline).
What reads successfully also prints back to the same IR.

Inputs: (a) text over the language's alphabet (parens, the three quotes,
keywords, symbols, ?variables, numbers, commas, comments, newlines, random
unicode), both as a token soup and as well-nested forms; (b) the bundled
domain and state files with a few characters or tokens deleted, inserted,
duplicated or swapped. Runs are derandomized, so they are reproducible.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cfgplan.check import check
from cfgplan.diagnostics import CfgplanError, Diagnostic
from cfgplan.ir.model import Domain, State
from cfgplan.syntax.printer import print_domain, print_state
from cfgplan.syntax.reader import SourceFile, domain_from, parse, state_from

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = sorted((ROOT / "domains").glob("*/*.lisp"))
TEXTS = {p: p.read_text("utf-8") for p in BUNDLED}

FUZZ = settings(
    max_examples=200,
    deadline=2000,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


# --- the property -----------------------------------------------------------


def _assert_diagnostics_located(diagnostics: list[Diagnostic], *, span_required: bool) -> None:
    for d in diagnostics:
        assert isinstance(d, Diagnostic)
        assert d.message.strip(), f"empty message: {d!r}"
        if d.span is None:
            assert not span_required, f"diagnostic without a span: {d.message}"
            continue
        assert d.span.line >= 1 and d.span.column >= 1, f"bad span {d.span!r}: {d.message}"


@cache
def _bundled_domain(folder: str) -> Domain:
    """The main domain of a bundled folder, to check mutated states against."""
    path = ROOT / "domains" / folder / "domain.lisp"
    return domain_from(parse(path.read_text("utf-8"), str(path)))


def _round_trip(before: Domain | State) -> None:
    """What was read prints back to the same IR (repr, so NaN == NaN and 2 != 2.0),
    and printing that again gives the same text."""
    after: Domain | State
    if isinstance(before, Domain):
        printed = print_domain(before)
        after = domain_from(parse(printed, "<printed>"))
        assert print_domain(after) == printed
    else:
        printed = print_state(before)
        after = state_from(parse(printed, "<printed>"))
        assert print_state(after) == printed
    assert repr(after.model_dump()) == repr(before.model_dump())


def _read_and_check(text: str, folder: str = "cross-door") -> list[Diagnostic]:
    """Run the front end on ``text``: read, print back, check. Only
    CfgplanError may escape, and it must be located; the diagnostics found."""
    try:
        source: SourceFile = parse(text, "fuzz.lisp")
        is_state = bool(source.states or source.goals)
        result = state_from(source) if is_state else domain_from(source)
    except CfgplanError as exc:
        assert exc.diagnostics, "a CfgplanError without diagnostics"
        _assert_diagnostics_located(exc.diagnostics, span_required=True)
        return exc.diagnostics
    _round_trip(result)
    try:
        if isinstance(result, Domain):
            found = check(result)
        else:
            found = check(_bundled_domain(folder), result, result.goal)
    except CfgplanError as exc:
        _assert_diagnostics_located(exc.diagnostics, span_required=True)
        return exc.diagnostics
    assert isinstance(found, list)
    _assert_diagnostics_located(found, span_required=True)
    return found


# --- (a) text from the language's alphabet -------------------------------------


def _words(text: str) -> list[str]:
    return text.split()


_PUNCTUATION = ["(", ")", "(", ")", "'", "’", "‘", ",", ";", ";; note\n", "\n", " ", "\t", "\r\n"]
_WORDS = [
    *_PUNCTUATION,
    *_words(":name :in :out :channels :body :precond :postcond :cost :freq :Name : ::"),
    *_words("make-functionality make-config-method state goal State"),
    *_words("not eval quote local global medium nil and eql <"),
    *_words("robot camera in Pippi Emil Door1 socket ?r ?f1 ?f2 ?d ? robot( in( foo("),
    *_words("0 20 -3 +4 2.5 1. .5 1e5 nan inf 007"),
    *['"', "#", "\\", "|", "\x00", "\x0b", "\x0c", "\u00a0", "\u2028", "\ufeff", "é", "🤖"],
]
_ALPHABET_TEXT = st.lists(st.one_of(st.sampled_from(_WORDS), st.text(max_size=3)), max_size=60).map(
    "".join
)

_SYMBOLS = st.sampled_from(
    _words(
        "robot camera image pos Pippi Emil Door1 not eval quote local global medium nil eql"
        " ?r ?d ?f1 ?f2 ?rh1 socket 20 -3 2.5 200 x:y"
    )
)
_SEXPR = st.recursive(
    _SYMBOLS,
    lambda inner: st.lists(inner, max_size=5).map(lambda xs: "(" + " ".join(xs) + ")"),
    max_leaves=25,
)
_QUOTES = st.sampled_from(["'", "’", "‘", ""])
_OPTION = st.builds(
    lambda k, q, v: f"{k} {q}{v}",
    st.sampled_from(
        [":name", ":in", ":out", ":channels", ":body", ":precond", ":postcond", ":cost", ":freq"]
    ),
    _QUOTES,
    _SEXPR,
)
_FORM = st.one_of(
    st.builds(
        lambda head, opts: f"({head} " + "\n  ".join(opts) + ")",
        st.sampled_from(["make-functionality", "make-config-method"]),
        st.lists(_OPTION, max_size=6),
    ),
    st.builds(lambda xs: "(state " + ", ".join(xs) + ")", st.lists(_SEXPR, max_size=8)),
    st.builds(lambda q, x: f"(goal {q}{x})", _QUOTES, _SEXPR),
)
_FORMS_TEXT = st.lists(_FORM, min_size=1, max_size=4).map("\n".join)

# Forms shaped like the real ones over a small vocabulary, so that most read
# successfully and the checker sees calls that resolve, mismatch and loop.
_VARS = st.sampled_from(["?r", "?d", "?o", "?rh1", "?x"])
_PREDS = st.sampled_from(["camera", "image", "pos", "measure", "get-info", "cross", "robot"])
_LABELS = st.sampled_from(["?f1", "?f2", "?f3"])
_NUMS = st.sampled_from(["", " 10", " 20.5", " 0", " -1"])


def _paren(parts: list[str]) -> str:
    return "(" + " ".join(parts) + ")"


_ATOM = st.builds(lambda p, a: _paren([p, *a]), _PREDS, st.lists(_VARS, max_size=3))
_ATOMS = st.lists(_ATOM, max_size=3).map(_paren)
_COND = st.one_of(
    _ATOM,
    _ATOM.map(lambda a: f"(not {a})"),
    st.builds(lambda a, b: f"(eval (not (eql (quote {a}) (quote {b}))))", _VARS, _VARS),
    _SEXPR.map(lambda x: f"(eval {x})"),
)
_PORT = st.builds(lambda f, a, n: f"({f} {a}{n})", _LABELS, _ATOM, _NUMS)
_CHANNEL = st.builds(
    lambda kind, f, g, a, n: f"({kind} {f} {g} {a}{n})",
    st.one_of(
        _VARS.map(lambda r: f"(local {r})"),
        st.builds(lambda r, s: f"(global {r} {s})", _VARS, _VARS),
    ),
    _LABELS,
    _LABELS,
    _ATOM,
    _NUMS,
)
_BODY = st.builds(lambda f, a: f"({f} {a})", _LABELS, _ATOM)


def _shaped_form(head: str, fields: dict[str, st.SearchStrategy[str]]) -> st.SearchStrategy[str]:
    opts = st.fixed_dictionaries({}, optional=fields)
    name = st.builds(lambda p, a: _paren([p, *a]), _PREDS, st.lists(_VARS, min_size=1, max_size=3))
    return st.builds(
        lambda n, o: (
            f"({head} :name '{n}\n  " + "\n  ".join(f"{k} '{v}" for k, v in o.items()) + ")"
        ),
        name,
        opts,
    )


_SHAPED_TEXT = st.lists(
    st.one_of(
        _shaped_form(
            "make-functionality",
            {":precond": st.lists(_COND, max_size=3).map(_paren), ":in": _ATOMS, ":out": _ATOMS},
        ),
        _shaped_form(
            "make-config-method",
            {
                ":precond": st.lists(_COND, max_size=3).map(_paren),
                ":postcond": _ATOMS,
                ":in": st.lists(_PORT, max_size=2).map(_paren),
                ":out": st.lists(_PORT, max_size=2).map(_paren),
                ":channels": st.lists(_CHANNEL, max_size=3).map(_paren),
                ":body": st.lists(_BODY, max_size=3).map(_paren),
            },
        ),
    ),
    min_size=1,
    max_size=6,
).map("\n".join)


@pytest.mark.quick(6)
@FUZZ
@given(_ALPHABET_TEXT)
def test_alphabet_soup(text: str) -> None:
    _read_and_check(text)


@pytest.mark.quick(25)
@FUZZ
@given(_FORMS_TEXT)
def test_nested_forms(text: str) -> None:
    _read_and_check(text)


@pytest.mark.quick(25)
@FUZZ
@given(_SHAPED_TEXT)
def test_shaped_domains(text: str) -> None:
    _read_and_check(text)


# --- (b) mutations of the bundled files ----------------------------------------

_TOKEN = re.compile(r"[()'’‘,]|;[^\n]*|\s+|[^\s()'’‘,;]+")


def _tokens(text: str) -> list[str]:
    return _TOKEN.findall(text)


@st.composite
def _mutant(draw: st.DrawFn) -> tuple[Path, str]:
    path = draw(st.sampled_from(BUNDLED))
    text = TEXTS[path]
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["delete", "insert", "duplicate", "swap"]))
        if draw(st.booleans()):  # a character
            units: list[str] = list(text)
            extra = st.one_of(st.sampled_from(list("()'’‘,;:?\n \"0.-")), st.characters())
        else:  # a token
            units = _tokens(text)
            extra = st.sampled_from([*_WORDS, *units[:50]])
        if not units:
            break
        i = draw(st.integers(0, len(units) - 1))
        if op == "delete":
            del units[i]
        elif op == "insert":
            units.insert(i, draw(extra))
        elif op == "duplicate":
            units.insert(i, units[i])
        else:
            j = draw(st.integers(0, len(units) - 1))
            units[i], units[j] = units[j], units[i]
        text = "".join(units)
    return path, text


@pytest.mark.quick(25)
@FUZZ
@given(_mutant())
def test_mutated_bundled_files(case: tuple[Path, str]) -> None:
    path, text = case
    _read_and_check(text, path.parent.name)


# --- fixed cases ----------------------------------------------------------------


@pytest.mark.parametrize("path", BUNDLED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_bundled_files_pass_the_property(path: Path) -> None:
    _read_and_check(TEXTS[path], path.parent.name)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "   \n",
        "; only a comment\n",
        "(",
        ")",
        "(state",
        "(make-functionality :name '(f ?r) :in '((x ?r))",
        "(state (robot Pippi)))",
        "(state (robot ?r))",
        "(goal (x ?r))",
        "(make-functionality :name '(f ?r) :bogus 1)",
        "(state " + "(" * 70 + "a" + ")" * 70 + ")",
        "(make-config-method :name '(m ?r) :precond '((eval " + "1" * 4000 + ")))",
    ],
)
def test_known_bad_inputs(text: str) -> None:
    _read_and_check(text)


def test_eval_numeral_past_int_digit_limit() -> None:
    """A 4301-digit numeral (past Python's int() limit) is a clear error, not a crash."""
    text = "(make-config-method :name '(m ?r) :precond '((eval " + "1" * 4301 + ")))"
    with pytest.raises(CfgplanError) as caught:
        parse(text, "fuzz.lisp")
    assert "more than 4000 characters" in str(caught.value)
    _read_and_check(text)  # and the fuzz property holds for it


def test_the_property_checks_what_reads() -> None:
    """What reads well is checked too: a body calling an undefined method is
    the checker's error, located on the call (not only the reader is fuzzed)."""
    text = (
        "(make-functionality :name '(camera ?r) :out '((image ?r)))\n"
        "(make-config-method :name '(see ?r)\n"
        "  :body '((?f1 (camera ?r)) (?f2 (measure-window ?r))))\n"
    )
    found = _read_and_check(text)
    (d,) = [d for d in found if d.is_error]
    assert "no functionality or method (measure-window ...)" in d.message
    assert d.span is not None and (d.span.line, d.span.column) == (3, 34)
