"""Small domains and lookups the checker's tests share (tests/check)."""

from __future__ import annotations

from cfgplan.check import check
from cfgplan.diagnostics import Diagnostic
from cfgplan.ir.model import Goal
from cfgplan.syntax.reader import domain_from, parse, state_from

# Three functionalities on lines 1-3; the tests append methods from line 4 on.
BASE = """\
(make-functionality :name '(camera ?r) :out '((image ?r)))
(make-functionality :name '(measure-door ?r ?d) :in '((image ?r)) :out '((pos ?r ?d)(orient ?r ?d)))
(make-functionality :name '(cross-door ?r ?d) :in '((pos ?r ?d) (orient ?r ?d)))
"""

GOOD = """\
(make-config-method :name '(get-door-info ?r ?d)
  :precond '((camera ?r) (door ?d))
  :out '((?f2 (pos ?r ?d)) (?f2 (orient ?r ?d)))
  :channels '(((local ?r) ?f1 ?f2 (image ?r)))
  :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))
"""


def at(text: str, needle: str, nth: int = 1) -> str:
    """``line:col`` of the ``nth`` occurrence of ``needle`` in ``text``."""
    index = -1
    for _ in range(nth):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    return f"{line}:{column}"


def run(text: str, state: str | None = None, goal: Goal | None = None) -> list[Diagnostic]:
    domain = domain_from(parse(text, "t.lisp"))
    world = state_from(parse(state, "s.lisp")) if state is not None else None
    return check(domain, world, goal)


def only(found: list[Diagnostic], severity: str = "error") -> Diagnostic:
    """The one diagnostic of ``severity`` (the message lists all if there are more)."""
    hits = [d for d in found if d.severity == severity]
    assert len(hits) == 1, "\n".join(f"{d.severity}: {d.message} @ {d.span}" for d in found)
    return hits[0]


def loc(d: Diagnostic) -> str:
    assert d.span is not None
    return f"{d.span.line}:{d.span.column}"
