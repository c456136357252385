"""The typed intermediate representation of domains and states (thesis 3.2-3.5, 4.4).

Every node keeps the source position it was read from in ``span``. Spans are
excluded from serialisation, so ``model_dump()`` compares two IRs by meaning
alone (the round-trip test relies on it).

Terms are plain strings: a variable starts with ``?`` (``?r``), anything else
is a constant (``Pippi``, ``Door1``, ``200``). Symbols are case-sensitive.
"""

# No ``from __future__ import annotations``: pydantic takes the models' annotations
# as objects, with no string to evaluate for each field (start-up, docs/development.md).
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field
from typing_extensions import TypeAliasType

from cfgplan.notation import atom_text, sexpr_text

Quantity = Annotated[float, Field(ge=0, allow_inf_nan=False)]
"""A bandwidth, frequency or capacity: finite and not negative."""

MAX_WEIGHT = 1e15
"""The largest weight of the cost (``--weights``) or ``:cost``: larger ones are
refused, so that costs stay finite (no ``inf`` or ``nan`` in the output, which
strict JSON parsers reject) and, for whole weights, whole numbers (a float holds
every whole number up to 2^53, about 9e15)."""

Weight = Annotated[float, Field(ge=0, le=MAX_WEIGHT, allow_inf_nan=False)]
"""A weight of the cost sum or a functionality's ``:cost``: a :data:`Quantity` of
at most :data:`MAX_WEIGHT`."""

Term = str
"""A variable (``?r``) or a constant (``Pippi``)."""


def is_variable(term: Term) -> bool:
    """True for a variable such as ``?r``."""
    return term.startswith("?")


class Span(BaseModel):
    """Where a node stands in its source file (1-based line and column)."""

    model_config = ConfigDict(frozen=True)

    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


def _span_field() -> Span | None:
    return Field(default=None, exclude=True, repr=False)


class Node(BaseModel):
    """Base of every IR node: immutable, with an optional source span."""

    model_config = ConfigDict(frozen=True)

    span: Span | None = _span_field()


class Atom(Node):
    """A predicate applied to terms: a fact ``(in Pippi Room1)``, a data
    descriptor ``(image ?r)`` or a call ``(camera ?r)``."""

    kind: Literal["atom"] = "atom"
    predicate: str
    args: tuple[Term, ...] = ()

    @property
    def arity(self) -> int:
        return len(self.args)

    @property
    def signature(self) -> tuple[str, int]:
        """Name and arity: the identity of a method or functionality (thesis 4.5)."""
        return (self.predicate, len(self.args))

    def variables(self) -> list[Term]:
        return [a for a in self.args if is_variable(a)]

    def __str__(self) -> str:
        return atom_text((self.predicate, *self.args))


class Negation(Node):
    """``(not ATOM)``: in a precondition, no fact matches; in a postcondition,
    the fact is deleted."""

    kind: Literal["not"] = "not"
    atom: Atom

    def __str__(self) -> str:
        return f"(not {self.atom})"


SExpr = TypeAliasType("SExpr", str | int | float | list["SExpr"])  # type: ignore[misc]
"""A raw s-expression: a symbol, a number, or a list of s-expressions."""


class Eval(Node):
    """``(eval EXPR)``: a test in the safe Lisp subset of
    :mod:`cfgplan.check.evaluate`. It is interpreted, never executed."""

    kind: Literal["eval"] = "eval"
    expr: SExpr

    def variables(self) -> list[Term]:
        return expr_variables(self.expr)

    def __str__(self) -> str:
        return f"(eval {sexpr_text(self.expr)})"


def expr_variables(expr: SExpr) -> list[Term]:
    """The variables of an s-expression, each once, in order of appearance."""
    found: list[Term] = []
    stack: list[SExpr] = [expr]
    while stack:
        item = stack.pop()
        if isinstance(item, list):
            stack.extend(reversed(item))
        elif isinstance(item, str) and is_variable(item) and item not in found:
            found.append(item)
    return found


Condition = Atom | Negation | Eval
"""A precondition: an atom, a negated atom or an eval test."""

Effect = Atom | Negation
"""A postcondition: an atom to add, or ``(not ATOM)`` to delete."""


class Functionality(Node):
    """A functionality operator ``<r, Id, I, O, Pr, Po, Freq, Cost>`` (3.2, 4.4).

    The first argument of ``name`` is the robot (or other agent) it runs on.
    """

    name: Atom
    inputs: tuple[Atom, ...] = ()
    outputs: tuple[Atom, ...] = ()
    precond: tuple[Condition, ...] = ()
    postcond: tuple[Effect, ...] = ()
    cost: Weight | None = None
    freq: Quantity | None = None
    reliability: Quantity | None = None  # the chance it works, in (0, 1] (7.2; beyond the thesis)


class Port(Node):
    """An entry of a method's ``:in`` or ``:out``: which body label consumes or
    produces the descriptor, with an optional bandwidth (4.4)."""

    label: str
    data: Atom
    bandwidth: Quantity | None = None


class ChannelSpec(Node):
    """A channel a method creates: ``((local ?r) ?f1 ?f2 (image ?r) [bw])`` or
    ``((global ?from ?to) ?f1 ?f2 (pos ?r ?d) [bw])`` (3.4, 4.4), or, beyond
    the thesis, ``((any ?from ?to) ...)``: local when ``?from`` and ``?to``
    are the same agent once instantiated, global otherwise."""

    kind: Literal["local", "global", "any"]
    robots: tuple[Term, ...]
    source: str
    target: str
    data: Atom
    bandwidth: Quantity | None = None


class BodyItem(Node):
    """A labelled functionality or method call in a method body."""

    label: str
    call: Atom


class Method(Node):
    """A configuration method (4.4). Several versions may share a name; a method
    is identified by name and arity."""

    name: Atom
    precond: tuple[Condition, ...] = ()
    postcond: tuple[Effect, ...] = ()
    inputs: tuple[Port, ...] = ()
    outputs: tuple[Port, ...] = ()
    channels: tuple[ChannelSpec, ...] = ()
    body: tuple[BodyItem, ...] = ()


class Domain(Node):
    """Functionality operators and methods, in file order (4.4)."""

    functionalities: tuple[Functionality, ...] = ()
    methods: tuple[Method, ...] = ()

    def functionality(self, signature: tuple[str, int]) -> Functionality | None:
        for f in self.functionalities:
            if f.name.signature == signature:
                return f
        return None

    def method_versions(self, signature: tuple[str, int]) -> list[Method]:
        """All versions of a method, in domain order (their order decides ties, 6.3.2)."""
        return [m for m in self.methods if m.name.signature == signature]


class Medium(Node):
    """``medium(type, from, to, capacity [reliability])``: a one-way
    communication medium (4.6); the reliability, in (0, 1], is an extension."""

    type: str
    sender: str
    receiver: str
    capacity: Quantity
    reliability: Quantity | None = None


class Goal(Node):
    """A method instance to plan for, e.g. ``(do-cross-door Pippi Door1)``."""

    call: Atom


class State(Node):
    """A world state: facts in order, media, and an optional goal (4.4)."""

    facts: tuple[Atom, ...] = ()
    media: tuple[Medium, ...] = ()
    goal: Goal | None = None
    sequence: tuple[Goal, ...] = ()  # (sequence G1 G2 ...): goals one after the other
