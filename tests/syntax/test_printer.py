"""The printer (thesis 4.4, Appendix A): parse -> print -> parse keeps the IR."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cfgplan.ir.model import (
    Atom,
    BodyItem,
    ChannelSpec,
    Condition,
    Domain,
    Effect,
    Eval,
    Functionality,
    Goal,
    Medium,
    Method,
    Negation,
    Port,
    SExpr,
    State,
)
from cfgplan.syntax.printer import format_functionality, print_domain, print_state
from cfgplan.syntax.reader import domain_from, parse, state_from

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = sorted((ROOT / "domains").glob("*/*.lisp"))
DOMAIN_FILES = [p for p in BUNDLED if not p.name.startswith("state-")]
STATE_FILES = [p for p in BUNDLED if p.name.startswith("state-")]


def _id(path: Path) -> str:
    return f"{path.parent.name}/{path.name}"


def read_domain_text(text: str) -> Domain:
    return domain_from(parse(text, "<printed>"))


def read_state_text(text: str) -> State:
    return state_from(parse(text, "<printed>"))


def test_bundled_files_found() -> None:
    assert len(DOMAIN_FILES) >= 4
    assert len(STATE_FILES) >= 8


# --- round trips over the bundled files -------------------------------------


@pytest.mark.parametrize("path", DOMAIN_FILES, ids=_id)
def test_domain_round_trip(path: Path) -> None:
    domain = domain_from(parse(path.read_text("utf-8"), str(path)))
    printed = print_domain(domain)
    again = read_domain_text(printed)
    assert again.model_dump() == domain.model_dump()
    assert printed.endswith("\n") and not printed.endswith("\n\n")


@pytest.mark.parametrize("path", STATE_FILES, ids=_id)
def test_state_round_trip(path: Path) -> None:
    state = state_from(parse(path.read_text("utf-8"), str(path)))
    printed = print_state(state)
    again = read_state_text(printed)
    assert again.model_dump() == state.model_dump()
    assert printed.endswith("\n")


@pytest.mark.parametrize("path", DOMAIN_FILES, ids=_id)
def test_domain_printing_is_idempotent(path: Path) -> None:
    printed = print_domain(domain_from(parse(path.read_text("utf-8"), str(path))))
    assert print_domain(read_domain_text(printed)) == printed


@pytest.mark.parametrize("path", STATE_FILES, ids=_id)
def test_state_printing_is_idempotent(path: Path) -> None:
    printed = print_state(state_from(parse(path.read_text("utf-8"), str(path))))
    assert print_state(read_state_text(printed)) == printed


def test_printed_notation_state_round_trip() -> None:
    text = (
        "(state robot(Pippi), robot(Emil), camera(Emil), in(Pippi, Room1),\n"
        "       medium(socket, Pippi, Emil, 200), medium(radio, Emil, Pippi, 12.5))\n"
        "(goal ’(do-cross-door Pippi Door1))\n"
    )
    state = read_state_text(text)
    printed = print_state(state)
    assert printed == (
        "(state (robot Pippi) (robot Emil) (camera Emil) (in Pippi Room1)\n"
        "       (medium socket Pippi Emil 200) (medium radio Emil Pippi 12.5))\n"
        "\n"
        "(goal (do-cross-door Pippi Door1))\n"
    )
    assert read_state_text(printed).model_dump() == state.model_dump()


# --- golden text ----------------------------------------------------------


def test_golden_functionality() -> None:
    domain = read_domain_text(
        "(make-functionality :name ’(measure-robot-orient-compass ?rh1 ?r) "
        ":precond ’( (compass ?rh1) (compass ?r) ) "
        ":in ’((global-orient ?rh1) (global-orient ?r)) :out ’((orient ?rh1 ?r)))"
    )
    assert format_functionality(domain.functionalities[0]) == (
        "(make-functionality :name '(measure-robot-orient-compass ?rh1 ?r)\n"
        "  :precond '((compass ?rh1) (compass ?r))\n"
        "  :in '((global-orient ?rh1) (global-orient ?r))\n"
        "  :out '((orient ?rh1 ?r)))"
    )


def test_golden_method_with_bandwidths() -> None:
    domain = read_domain_text(
        "(make-config-method :name '(get-door-info ?r ?d) :precond '((camera ?r))"
        " :out '((?f2 (pos ?r ?d) 20) (?f2 (orient ?r ?d) 10.5))"
        " :channels '(((local ?r) ?f1 ?f2 (image ?r) 50.0))"
        " :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))"
    )
    assert print_domain(domain) == (
        "(make-config-method :name '(get-door-info ?r ?d)\n"
        "  :precond '((camera ?r))\n"
        "  :out '((?f2 (pos ?r ?d) 20) (?f2 (orient ?r ?d) 10.5))\n"
        "  :channels '(((local ?r) ?f1 ?f2 (image ?r) 50))\n"
        "  :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))\n"
    )


def test_eval_quote_postcond_cost_freq() -> None:
    text = (
        "(make-functionality :name '(f ?r) :cost 3 :freq 2.5"
        " :postcond '((not (busy ?r)) (done ?r 7)))\n"
        "(make-config-method :name '(m ?a ?b)"
        " :precond '((eval (and (not (eql '?a '?b)) (< 1 2.0 -3 +4))) (not (robot ?a)))"
        " :in '((?f1 (x ?a)))"
        " :body '((?f1 (f ?a))))\n"
    )
    domain = read_domain_text(text)
    printed = print_domain(domain)
    assert ":cost 3\n  :freq 2.5)" in printed
    assert ":postcond '((not (busy ?r)) (done ?r 7))" in printed
    assert "(eval (and (not (eql (quote ?a) (quote ?b))) (< 1 2.0 -3 4)))" in printed
    assert read_domain_text(printed).model_dump() == domain.model_dump()


def test_empty_state_and_no_goal() -> None:
    assert print_state(State()) == "(state)\n"
    assert read_state_text(print_state(State())).model_dump() == State().model_dump()


def test_output_is_deterministic() -> None:
    path = DOMAIN_FILES[0]
    text = path.read_text("utf-8")
    assert print_domain(read_domain_text(text)) == print_domain(read_domain_text(text))


# --- generated IRs ----------------------------------------------------------

_LOWER = "abcdefghijklmnopqrstuvwxyz"
_UPPER = _LOWER.upper()
_DIGITS = "0123456789"


def _word(first: str, rest: str, max_rest: int) -> st.SearchStrategy[str]:
    """A symbol: one character of ``first``, then up to ``max_rest`` of ``rest``."""
    return st.builds(str.__add__, st.sampled_from(first), st.text(alphabet=rest, max_size=max_rest))


_NAME = _word(_LOWER, _LOWER + _DIGITS + "-", 6).filter(
    lambda s: s not in ("not", "eval", "quote", "nil", "medium", "local", "global")
)
_CONST = _word(_UPPER, _LOWER + _UPPER + _DIGITS, 5)
_VAR = _word(_LOWER, _LOWER + _DIGITS, 3).map(lambda s: "?" + s)
_NUMERAL = st.builds(
    lambda sign, whole, frac: sign + whole + frac,
    st.sampled_from(["", "-", "+"]),
    st.text(alphabet=_DIGITS, min_size=1, max_size=4),
    st.sampled_from(["", ".5", ".25", ".0", ".125"]),
)
_TERM = st.one_of(_VAR, _CONST, _NUMERAL)
# What the language writes for a bandwidth, cost, frequency or capacity:
# a finite number >= 0 with a few decimals.
_QUANTITY = st.one_of(
    st.integers(0, 10**12).map(float),
    st.builds(lambda whole, frac: whole + frac / 1000, st.integers(0, 10**6), st.integers(0, 999)),
)


def _atoms(terms: st.SearchStrategy[str], min_args: int = 0) -> st.SearchStrategy[Atom]:
    return st.builds(
        Atom, predicate=_NAME, args=st.lists(terms, min_size=min_args, max_size=3).map(tuple)
    )


_SEXPR: st.SearchStrategy[SExpr] = st.recursive(
    st.one_of(
        _NAME,
        _VAR,
        st.integers(-(10**30), 10**30),
        st.floats(min_value=-1e12, max_value=1e12, allow_nan=False, allow_infinity=False),
    ),
    lambda inner: st.lists(inner, max_size=4),
    max_leaves=12,
)
_CONDITION: st.SearchStrategy[Condition] = st.one_of(
    _atoms(_TERM),
    st.builds(Negation, atom=_atoms(_TERM)),
    st.builds(Eval, expr=_SEXPR),
)
_EFFECT: st.SearchStrategy[Effect] = st.one_of(
    _atoms(_TERM), st.builds(Negation, atom=_atoms(_TERM))
)


def _tuples(strategy: st.SearchStrategy[Any], max_size: int = 3) -> st.SearchStrategy[Any]:
    return st.lists(strategy, max_size=max_size).map(tuple)


_FUNCTIONALITY = st.builds(
    Functionality,
    name=_atoms(_TERM, min_args=1),
    inputs=_tuples(_atoms(_TERM)),
    outputs=_tuples(_atoms(_TERM)),
    precond=_tuples(_CONDITION),
    postcond=_tuples(_EFFECT),
    cost=st.none() | _QUANTITY,
    freq=st.none() | _QUANTITY,
)
_PORT = st.builds(Port, label=_VAR, data=_atoms(_TERM), bandwidth=st.none() | _QUANTITY)


@st.composite
def _channels(draw: st.DrawFn) -> ChannelSpec:
    kind = draw(st.sampled_from(["local", "global"]))
    robots = tuple(
        draw(
            st.lists(_VAR, min_size=1, max_size=1)
            if kind == "local"
            else st.lists(_VAR, min_size=2, max_size=2)
        )
    )
    return ChannelSpec(
        kind=kind,
        robots=robots,
        source=draw(_VAR),
        target=draw(_VAR),
        data=draw(_atoms(_TERM)),
        bandwidth=draw(st.none() | _QUANTITY),
    )


_METHOD = st.builds(
    Method,
    name=_atoms(_TERM),
    precond=_tuples(_CONDITION),
    postcond=_tuples(_EFFECT),
    inputs=_tuples(_PORT),
    outputs=_tuples(_PORT),
    channels=_tuples(_channels()),
    body=_tuples(st.builds(BodyItem, label=_VAR, call=_atoms(_TERM))),
)
_DOMAIN = st.builds(
    Domain,
    functionalities=_tuples(_FUNCTIONALITY),
    methods=_tuples(_METHOD),
).filter(lambda d: bool(d.functionalities or d.methods))
_GROUND = st.one_of(_CONST, _NUMERAL)
_STATE = st.builds(
    State,
    facts=_tuples(_atoms(_GROUND), 12),
    media=_tuples(
        st.builds(
            Medium,
            type=_NAME,
            sender=_CONST,
            receiver=_CONST,
            capacity=_QUANTITY,
        ),
        4,
    ),
    goal=st.none() | st.builds(Goal, call=_atoms(_GROUND)),
)


@pytest.mark.quick(20)
@settings(max_examples=100, derandomize=True, deadline=2000)
@given(_DOMAIN)
def test_generated_domain_round_trip(domain: Domain) -> None:
    printed = print_domain(domain)
    again = read_domain_text(printed)
    assert again.model_dump() == domain.model_dump()
    assert print_domain(again) == printed


@settings(max_examples=100, derandomize=True, deadline=2000)
@given(_STATE)
def test_generated_state_round_trip(state: State) -> None:
    printed = print_state(state)
    again = read_state_text(printed)
    assert again.model_dump() == state.model_dump()
    assert print_state(again) == printed
