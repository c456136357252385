"""What the fuzzer feeds cfgplan: Hypothesis strategies for (domain, state) pairs.

Three families, drawn by :data:`CASES` (mutated and generated about half
each, chains one in a hundred):

* **mutated**: a bundled domain and one of its states (``domains/``), with 1-4
  byte-level mutations of one or both files: bit flips, deleted, duplicated
  or spliced ranges, truncation, bytes that matter to the reader or to a
  terminal (parentheses, quotes, ``;``, CR, NUL, a BOM, U+2028, invalid UTF-8,
  ESC, 400-digit numbers, deep nesting), a robot or door renamed everywhere to
  a hostile name (``../../x``, ``CON``, ``a\\b``, ``#|x``), or a fact repeated;
* **generated**: domains and states built from the grammar over a small
  vocabulary, shaped like the real ones (methods with preconditions,
  channels and bodies calling each other), or a bundled domain with a state
  of random facts over the bundled states' predicates and a goal, so that
  many reach the planner and the backends;
* **chains**: method hierarchies 1 to 600 levels deep.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Case:
    """One input: the bytes of a domain file and of a state file."""

    family: str
    domain: bytes
    state: bytes


def bundled_pairs() -> list[tuple[bytes, bytes]]:
    """Each bundled domain with each state of its folder that it plans for."""
    pairs = []
    for domain in sorted((ROOT / "domains").glob("*/domain*.lisp")):
        for state in sorted(domain.parent.glob("state-*.lisp")):
            media = "media" in state.name
            if media == ("bandwidth" in domain.name):
                pairs.append((domain.read_bytes(), state.read_bytes()))
    return pairs


PAIRS = bundled_pairs()
CHUNKS = [text for pair in PAIRS for text in pair]
NAMES = [b"Pippi", b"Emil", b"Rasmus", b"Door1", b"Room1", b"Room2", b"Bar1"]
HOSTILE = [
    b"../../escaped",
    b"/tmp/cfgplan-fuzz-abs",
    b"..",
    b"a\\b",
    b"D\\x1",
    b"a\x00b",
    b"CON",
    b"nul",
    b"x" * 300,
    b"#|Door1",
    b"a|b",
    b"x:y",
    b"\x1b[31mred\x07",
    b"\xe2\x80\xaeevil",
    b"-rf",
    b"run_all",
    b"configuration",
    "Ünïcödé".encode(),
    "🤖".encode(),
    b"emil",
    b"EMIL",
    b"1e5",
    b"20",
]
INTERESTING = [
    b"(",
    b")",
    b"'",
    "’".encode(),
    b",",
    b";",
    b'"',
    b":",
    b"?",
    b"\r",
    b"\n",
    b"\r\n",
    b"\t",
    b"\x00",
    b"\x0b",
    b"\x0c",
    b"\xef\xbb\xbf",
    "\u2028".encode(),
    b"\xc2\x85",
    b"\xff",
    b"\xc3",
    b"\x1b[2J",
    b"\x07",
    b"#|",
    b"|#",
    b"\\",
    b"9" * 400,
    b"1" * 4301,
    b"-1",
    b"0.5",
    b"nan",
    b"inf",
    b"(" * 70,
    b")" * 40,
    b" (eval (+ 1 2)) ",
    b" (eval (quote x)) ",
    b" (not ",
    b" :bogus 1 ",
    b" :cost 1e400 ",
    b" (medium socket Pippi Emil 10) ",
    b" (robot Pippi) ",
    b" (goal (do-cross-door Pippi Door1)) ",
    b"(make-config-method :name '(m ?r) :body '((?f1 (m ?r))))",
]

_offsets = st.integers(0, 1 << 30)


@st.composite
def _mutate(draw: st.DrawFn, data: bytes) -> bytes:
    out = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(
            st.sampled_from(
                ["flip", "insert", "delete", "duplicate", "splice", "truncate", "rename", "repeat"]
            )
        )
        at = draw(_offsets) % (len(out) + 1)
        if op == "flip" and out:
            out[at % len(out)] ^= 1 << draw(st.integers(0, 7))
        elif op == "insert":
            out[at:at] = draw(st.sampled_from(INTERESTING))
        elif op == "delete":
            del out[at : at + draw(st.integers(1, 64))]
        elif op == "duplicate" and out:
            start = draw(_offsets) % len(out)
            out[at:at] = out[start : start + draw(st.integers(1, 200))]
        elif op == "splice":
            chunk = draw(st.sampled_from(CHUNKS))
            start = draw(_offsets) % len(chunk)
            out[at:at] = chunk[start : start + draw(st.integers(1, 300))]
        elif op == "truncate":
            del out[at:]
        elif op == "rename":
            out = bytearray(
                bytes(out).replace(draw(st.sampled_from(NAMES)), draw(st.sampled_from(HOSTILE)))
            )
        elif op == "repeat":
            line_start = bytes(out).rfind(b"(", 0, at)
            line_end = bytes(out).find(b")", at)
            if 0 <= line_start < line_end:
                fact = bytes(out[line_start : line_end + 1]) + b" "
                out[line_start:line_start] = fact * draw(st.integers(1, 40))
    return bytes(out)


@st.composite
def mutated(draw: st.DrawFn) -> Case:
    domain, state = draw(st.sampled_from(PAIRS))
    which = draw(st.sampled_from(["domain", "state", "both"]))
    if which in ("domain", "both"):
        domain = draw(_mutate(domain))
    if which in ("state", "both"):
        state = draw(_mutate(state))
    return Case("mutated", domain, state)


# -- generated from the grammar ------------------------------------------------------

_VARS = st.sampled_from(["?r", "?d", "?o", "?x"])
_PREDS = st.sampled_from(["sense", "view", "pos", "act", "get", "use"])
_CONSTS = st.sampled_from(["Pippi", "Emil", "Door1", "a\\b", "../x", "CON"])
_LABELS = st.sampled_from(["?f1", "?f2", "?f3"])


def _paren(*parts: str) -> str:
    return "(" + " ".join(parts) + ")"


_ATOM = st.builds(lambda p, a: _paren(p, *a), _PREDS, st.lists(_VARS, min_size=1, max_size=2))
_NUM = st.sampled_from(["", " 10", " 0", " 2.5"])
_COND = st.one_of(
    _ATOM,
    _ATOM.map(lambda a: f"(not {a})"),
    st.builds(lambda a, b: f"(eval (not (eql (quote {a}) (quote {b}))))", _VARS, _VARS),
)
_CHANNEL = st.builds(
    lambda kind, f, g, a, n: f"({kind} {f} {g} {a}{n})",
    st.one_of(
        _VARS.map(lambda r: f"(local {r})"),
        st.builds(lambda r, s: f"(global {r} {s})", _VARS, _VARS),
    ),
    _LABELS,
    _LABELS,
    _ATOM,
    _NUM,
)
_FUNCTIONALITY = st.builds(
    lambda n, i, o, p: f"(make-functionality :name '{n} :in '{i} :out '{o} :precond '{p})",
    _ATOM,
    st.lists(_ATOM, max_size=2).map(lambda xs: _paren(*xs)),
    st.lists(_ATOM, max_size=2).map(lambda xs: _paren(*xs)),
    st.lists(_COND, max_size=2).map(lambda xs: _paren(*xs)),
)
_METHOD = st.builds(
    lambda n, p, o, c, b: (
        f"(make-config-method :name '{n} :precond '{p} :out '{o} :channels '{c} :body '{b})"
    ),
    _ATOM,
    st.lists(_COND, max_size=2).map(lambda xs: _paren(*xs)),
    st.lists(st.builds(lambda f, a: f"({f} {a})", _LABELS, _ATOM), max_size=2).map(
        lambda xs: _paren(*xs)
    ),
    st.lists(_CHANNEL, max_size=3).map(lambda xs: _paren(*xs)),
    st.lists(st.builds(lambda f, a: f"({f} {a})", _LABELS, _ATOM), min_size=1, max_size=3).map(
        lambda xs: _paren(*xs)
    ),
)
_FACT = st.builds(lambda p, a: _paren(p, *a), _PREDS, st.lists(_CONSTS, min_size=1, max_size=2))


@st.composite
def generated(draw: st.DrawFn) -> Case:
    """Half the time a domain built from the grammar (mostly refused by the
    checker: its error paths), half a bundled domain with a state built from
    the predicates of the bundled states (reaching the planner and backends)."""
    if draw(st.booleans()):
        domain, _ = draw(st.sampled_from(PAIRS))
        goals = [goal for method, goal in _GOALS.items() if method in domain]
        facts = draw(st.lists(_BUNDLED_FACT, max_size=25))
        goal = draw(st.one_of(*goals))
        state = f"(state {' '.join(facts)})\n(goal {goal})\n"
        return Case("generated", domain, state.encode())
    forms = draw(st.lists(st.one_of(_FUNCTIONALITY, _METHOD), min_size=1, max_size=8))
    facts = draw(st.lists(_FACT, max_size=10))
    goal = draw(
        st.builds(lambda p, a: _paren(p, *a), _PREDS, st.lists(_CONSTS, min_size=1, max_size=2))
    )
    state = f"(state {' '.join(facts)})\n(goal {goal})\n"
    return Case("generated", "\n".join(forms).encode(), state.encode())


_ROBOTS = st.sampled_from(["Pippi", "Emil", "Rasmus", "../x", "EMIL", "a\\b"])
_THINGS = st.sampled_from(["Door1", "Room1", "Room2", "Bar1", "B1", "W1", "#|x"])
_BUNDLED_FACT = st.one_of(
    st.builds(
        lambda p, r: f"({p} {r})",
        st.sampled_from(
            ["robot", "camera", "compass", "laser", "sonar", "pusher", "left", "right"]
        ),
        _ROBOTS,
    ),
    st.builds(
        lambda p, t: f"({p} {t})", st.sampled_from(["door", "open", "block", "wall"]), _THINGS
    ),
    st.builds(lambda a, b: f"(in {a} {b})", st.one_of(_ROBOTS, _THINGS), _THINGS),
    st.builds(lambda d, a, b: f"(connects {d} {a} {b})", _THINGS, _THINGS, _THINGS),
    st.builds(
        lambda a, b, c: f"(medium socket {a} {b} {c})", _ROBOTS, _ROBOTS, st.integers(0, 300)
    ),
)
_GOALS = {
    b"do-cross-door": st.builds(lambda r, d: f"(do-cross-door {r} {d})", _ROBOTS, _THINGS),
    b"do-carry-bar": st.builds(lambda r: f"(do-carry-bar {r})", _ROBOTS),
    b"do-push-block": st.builds(lambda b, w: f"(do-push-block {b} {w})", _THINGS, _THINGS),
}


def chain(levels: int) -> bytes:
    """A goal (top ?r) reaching (sense ?r) through ``levels`` methods."""
    lines = [
        "(make-functionality :name '(sense ?r) :out '((data ?r)))",
        "(make-functionality :name '(act ?r) :in '((data ?r)))",
    ]
    for i in range(levels):
        below = f"(m{i + 1} ?r)" if i + 1 < levels else "(sense ?r)"
        lines.append(
            f"(make-config-method :name '(m{i} ?r) :out '((?f1 (data ?r))) :body '((?f1 {below})))"
        )
    lines.append(
        "(make-config-method :name '(top ?r) :channels '(((local ?r) ?f1 ?f2 (data ?r)))"
        " :body '((?f1 (m0 ?r)) (?f2 (act ?r))))"
    )
    return ("\n".join(lines) + "\n").encode()


chains = st.builds(
    lambda n: Case("chains", chain(n), b"(state (robot Pippi))\n(goal (top Pippi))\n"),
    st.integers(1, 600),
)


def _family(k: int) -> st.SearchStrategy[Case]:
    return chains if k == 0 else mutated() if k % 2 else generated()


CASES = st.integers(0, 99).flatmap(_family)
"""What :mod:`benchmarks.fuzz` draws: mutations and generated problems, a few chains."""
