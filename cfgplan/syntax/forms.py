"""Interpreting the forms of the language (thesis 4.4, Appendix A) into the IR.

The grammar gives each keyword's value as a raw :class:`Sx` tree; the
functions here check its shape and build the pydantic IR, raising a
positioned error at the first thing that does not fit.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, TypeVar

from cfgplan.diagnostics import CfgplanError, did_you_mean, error
from cfgplan.ir.model import (
    MAX_WEIGHT,
    Atom,
    BodyItem,
    ChannelSpec,
    Condition,
    Effect,
    Eval,
    Functionality,
    Goal,
    Medium,
    Method,
    Negation,
    Port,
    Span,
    State,
)
from cfgplan.option_values import kept, rounding
from cfgplan.syntax.sx import Sx

FUNCTIONALITY_KEYWORDS = (
    ":name",
    ":in",
    ":out",
    ":precond",
    ":postcond",
    ":cost",
    ":freq",
    ":reliability",
)
METHOD_KEYWORDS = (":name", ":precond", ":postcond", ":in", ":out", ":channels", ":body")

T = TypeVar("T")


class Option(NamedTuple):
    """``:keyword value`` inside a make-functionality or make-config-method form
    (a named tuple: a frozen dataclass takes four times as long to define)."""

    keyword: str
    where: Sx
    """The keyword as read: its span is made only when an error asks for it
    (:class:`~cfgplan.syntax.sx.Sx`; a Span made at once for each of a big
    domain's 4,800 keywords went unused)."""
    value: Sx

    @property
    def span(self) -> Span:
        """Where the keyword stands."""
        return self.where.span


def _options(
    form: str, span: Span, children: Sequence[Any], allowed: tuple[str, ...]
) -> dict[str, Option]:
    found: dict[str, Option] = {}
    for opt in children:
        if not isinstance(opt, Option):
            continue
        if opt.keyword not in allowed:
            hint = f"{form} takes " + ", ".join(allowed)
            near = did_you_mean(opt.keyword, allowed)
            if near is not None:  # :ouput: did you mean :out? make-functionality takes ...
                hint = f"{near} {hint}"
            if opt.keyword.lower() in allowed:
                hint = f"keywords are case-sensitive: write {opt.keyword.lower()}"
            raise error(f"unknown keyword {opt.keyword} in {form}", opt.span, hint)
        if opt.keyword in found:
            raise error(f"{opt.keyword} is given twice in this {form}", opt.span)
        found[opt.keyword] = opt
    if ":name" not in found:
        raise error(f"{form} has no :name", span, "add :name '(NAME ?robot ...)")
    return found


def _elements(node: Sx, what: str) -> tuple[Sx, ...]:
    """The items of a list value; ``nil`` and ``()`` are the empty list."""
    if node.is_symbol and node.text.lower() == "nil":
        return ()
    if not node.is_list:
        raise error(f"expected a list of {what}, found {node}", node.span)
    items = node.items
    # A quoted value written inside the list, '(quote (...)) is kept as is.
    if node.head() == "quote" and len(items) == 2 and items[1].is_list:
        return items[1].items
    return items


def atom(node: Sx, what: str = "an atom such as (camera ?r)") -> Atom:
    """``(predicate term ...)`` with symbols or numbers as terms."""
    if not node.is_list or not node.items:
        raise error(f"expected {what}, found {node if node.is_list else node.text}", node.span)
    head, *args = node.items
    if not head.is_symbol:
        raise error(f"an atom starts with a name, found {head}", head.span)
    for arg in args:
        if arg.is_list and arg.head() == "quote":
            raise error(
                f"a quote inside ({head.text} ...): the arguments of an atom are not quoted",
                arg.span,
                f"write {arg.items[1] if len(arg.items) > 1 else 'the symbol'} without the quote",
            )
        if arg.is_list:
            raise error(
                f"an argument of ({head.text} ...) must be a symbol or a number, found a list",
                arg.span,
                "atoms are flat: (in Pippi Room1)",
            )
    return Atom(predicate=head.text, args=tuple(a.text for a in args), span=node.span)


def quantity(text: str) -> float | None:
    """A bandwidth, cost, frequency or capacity: a finite number >= 0, written
    as digits with an optional fraction (no nan, inf, exponents or '_')."""
    if not _QUANTITY.fullmatch(text):
        return None
    value = float(text)
    return value if math.isfinite(value) else None


_QUANTITY = re.compile(r"\+?\d{1,300}(\.\d{1,300})?")


def _number(node: Sx, what: str, most: float | None = None) -> float:
    value = quantity(node.text) if node.kind == "number" else None
    if value is None:
        raise error(
            f"expected a number for {what}, found {node}",
            node.span,
            "write digits with an optional fraction; quantities are not negative",
        )
    if most is not None and value > most:
        raise error(
            f"{what} is at most {most:g}, found {node}",
            node.span,
            "weights and :cost are at most 1e+15, so that a configuration's cost stays exact",
        )
    return _kept(node.text, value, node.span)


def _kept(text: str, value: float, span: Span | None) -> float:
    """``value`` if it is the number ``text`` writes, else an error: cfgplan's
    numbers are floats, and what the user wrote is never silently rounded."""
    if not kept(text, value):
        raise error(rounding(text, value), span, "write at most 15 significant digits")
    return value


def probability(text: str) -> float | None:
    """A reliability: a quantity in (0, 1]."""
    value = quantity(text)
    return value if value is not None and 0 < value <= 1 else None


def _reliability(node: Sx) -> float:
    value = probability(node.text) if node.kind == "number" else None
    if value is None:
        raise error(
            f"expected a reliability for :reliability, found {node}",
            node.span,
            "a reliability is the chance it works: a number above 0 and at most 1, e.g. 0.95",
        )
    return _kept(node.text, value, node.span)


def condition(node: Sx) -> Condition:
    """A precondition: an atom, ``(not ATOM)`` or ``(eval EXPR)``."""
    head = node.head()
    if head == "not":
        if len(node.items) != 2:
            raise error("(not ...) takes exactly one atom", node.span)
        return Negation(atom=atom(node.items[1]), span=node.span)
    if head == "eval":
        if len(node.items) != 2:
            raise error("(eval ...) takes exactly one expression", node.span)
        return Eval(expr=node.items[1].to_sexpr(), span=node.span)
    return atom(node, "a condition: an atom, (not ATOM) or (eval EXPR)")


def effect(node: Sx) -> Effect:
    """A postcondition: an atom to add, or ``(not ATOM)`` to delete."""
    if node.head() == "not":
        if len(node.items) != 2:
            raise error("(not ...) takes exactly one atom", node.span)
        return Negation(atom=atom(node.items[1]), span=node.span)
    return atom(node, "a postcondition: an atom or (not ATOM)")


def _each(opts: dict[str, Option], key: str, what: str, fn: Callable[[Sx], T]) -> tuple[T, ...]:
    if key not in opts:
        return ()
    return tuple(fn(item) for item in _elements(opts[key].value, what))


def _label(node: Sx, where: str) -> str:
    if not node.is_symbol:
        raise error(f"expected a label such as ?f1 in {where}, found {node}", node.span)
    return node.text


def _optional_bandwidth(items: Sequence[Sx], index: int, where: str) -> float | None:
    if len(items) <= index:
        return None
    if len(items) > index + 1:
        raise error(f"too many elements in {where}", items[index + 1].span)
    return _number(items[index], "the bandwidth")


def port(node: Sx) -> Port:
    """A method :in/:out entry ``(?f2 (pos ?r ?d) [bandwidth])``."""
    where = "a method :in/:out entry (?f (descriptor ...) [bandwidth])"
    if not node.is_list or len(node.items) < 2:
        raise error(f"expected {where}, found {node}", node.span)
    items = node.items
    return Port(
        label=_label(items[0], where),
        data=atom(items[1], "a data descriptor such as (pos ?r ?d)"),
        bandwidth=_optional_bandwidth(items, 2, where),
        span=node.span,
    )


CHANNEL_KINDS = {
    "local": "(local ?robot)",
    "global": "(global ?from ?to)",
    "any": "(any ?from ?to)",
}
"""The channel kinds (3.4, 4.4) and how each names its robots. ``any`` is an
extension beyond the thesis: local when ``?from`` and ``?to`` are one agent,
global otherwise."""


def channel(node: Sx) -> ChannelSpec:
    """``((local ?r) ?f1 ?f2 (image ?r) [bw])``, ``((global ?a ?b) ...)`` or
    ``((any ?a ?b) ...)``."""
    where = "a channel ((local ?r) ?f1 ?f2 (descriptor ...) [bandwidth])"
    if not node.is_list or len(node.items) < 4:
        raise error(f"expected {where}, found {node}", node.span)
    kind_node, src, dst, data, *_ = node.items
    kind = atom(kind_node, "(local ?r), (global ?from ?to) or (any ?from ?to)")
    if kind.predicate not in CHANNEL_KINDS:
        hint = None
        if kind.predicate.lower() in CHANNEL_KINDS:
            hint = f"symbols are case-sensitive: write {kind.predicate.lower()}"
        raise error(
            f"a channel is local, global or any, found {kind.predicate}", kind_node.span, hint
        )
    form = CHANNEL_KINDS[kind.predicate]
    want = len(form.split()) - 1
    if kind.arity != want:
        raise error(f"{kind.predicate} takes {want} robot(s): {form}", kind_node.span)
    return ChannelSpec(
        kind=kind.predicate,
        robots=kind.args,
        source=_label(src, where),
        target=_label(dst, where),
        data=atom(data, "a data descriptor such as (image ?r)"),
        bandwidth=_optional_bandwidth(node.items, 4, where),
        span=node.span,
    )


def body_item(node: Sx) -> BodyItem:
    """``(?f1 (camera ?r))``."""
    where = "a body entry (?f1 (name ?robot ...))"
    if not node.is_list or len(node.items) != 2:
        raise error(f"expected {where}, found {node}", node.span)
    return BodyItem(label=_label(node.items[0], where), call=atom(node.items[1]), span=node.span)


def _name(opts: dict[str, Option], form: str) -> Atom:
    name = atom(opts[":name"].value, "a name such as (camera ?r)")
    if form == "make-functionality" and not name.args:
        raise error(
            "a functionality's name needs the robot it runs on: (NAME ?robot ...)",
            name.span,
        )
    return name


def declared(children: Sequence[Any]) -> str | None:
    """The name a form's ``:name`` declares (``camera`` for ``:name '(camera
    ?r)``), read even when the rest of the form is wrong; None when it does
    not read either."""
    for opt in children:
        if isinstance(opt, Option) and opt.keyword == ":name":
            try:
                return atom(opt.value).predicate
            except CfgplanError:
                return None
    return None


def functionality(span: Span, children: Sequence[Any]) -> Functionality:
    """``(make-functionality :name ... :in ... :out ... :precond ... :postcond ...)``."""
    form = "make-functionality"
    opts = _options(form, span, children, FUNCTIONALITY_KEYWORDS)
    cost = _number(opts[":cost"].value, ":cost", MAX_WEIGHT) if ":cost" in opts else None
    freq = _number(opts[":freq"].value, ":freq") if ":freq" in opts else None
    reliability = _reliability(opts[":reliability"].value) if ":reliability" in opts else None
    return Functionality(
        name=_name(opts, form),
        inputs=_each(opts, ":in", "data descriptors", atom),
        outputs=_each(opts, ":out", "data descriptors", atom),
        precond=_each(opts, ":precond", "conditions", condition),
        postcond=_each(opts, ":postcond", "postconditions", effect),
        cost=cost,
        freq=freq,
        reliability=reliability,
        span=span,
    )


def method(span: Span, children: Sequence[Any]) -> Method:
    """``(make-config-method :name ... :precond ... :in ... :out ... :channels ... :body ...)``."""
    form = "make-config-method"
    opts = _options(form, span, children, METHOD_KEYWORDS)
    return Method(
        name=_name(opts, form),
        precond=_each(opts, ":precond", "conditions", condition),
        postcond=_each(opts, ":postcond", "postconditions", effect),
        inputs=_each(opts, ":in", ":in entries", port),
        outputs=_each(opts, ":out", ":out entries", port),
        channels=_each(opts, ":channels", "channels", channel),
        body=_each(opts, ":body", "body entries", body_item),
        span=span,
    )


def _medium(fact: Atom) -> Medium:
    if fact.arity not in (4, 5):
        raise error(
            "a medium is (medium TYPE FROM TO CAPACITY [RELIABILITY])",
            fact.span,
            "e.g. (medium socket Pippi Emil 200)",
        )
    mtype, sender, receiver, capacity, *rest = fact.args
    cap = quantity(capacity)
    if cap is None:
        raise error(
            f"the capacity of a medium is a number >= 0, found {capacity}",
            fact.span,
            "e.g. (medium socket Pippi Emil 200)",
        )
    _kept(capacity, cap, fact.span)
    reliability = probability(rest[0]) if rest else None
    if rest and reliability is None:
        raise error(
            f"the reliability of a medium is a number above 0 and at most 1, found {rest[0]}",
            fact.span,
            "e.g. (medium wifi Pippi Emil 200 0.9)",
        )
    if rest and reliability is not None:
        _kept(rest[0], reliability, fact.span)
    return Medium(
        type=mtype,
        sender=sender,
        receiver=receiver,
        capacity=cap,
        reliability=reliability,
        span=fact.span,
    )


def state(span: Span, children: Sequence[Any]) -> State:
    """``(state (robot Pippi) ...)`` or ``(state robot(Pippi), ...)``; media apart."""
    facts: list[Atom] = []
    media: list[Medium] = []
    nodes = [node for node in children if isinstance(node, Sx)]
    for i, node in enumerate(nodes):
        after = nodes[i + 1] if i + 1 < len(nodes) else None
        if node.is_symbol and after is not None and after.is_list:
            raise error(
                f"expected a fact such as (robot Pippi), found {node.text}",
                node.span,
                f"in the printed notation no space precedes '(': write {node.text}{after}",
            )
        fact = atom(node, "a fact such as (robot Pippi)")
        for arg in fact.args:
            if arg.startswith("?"):
                raise error(f"a fact holds no variables, found {arg} in {fact}", node.span)
        if fact.predicate == "medium":
            media.append(_medium(fact))
        else:
            facts.append(fact)
    return State(facts=tuple(facts), media=tuple(media), span=span)


def goal(span: Span, node: Sx) -> Goal:
    """``(goal (do-cross-door Pippi Door1))``."""
    call = atom(node, "a method instance such as (do-cross-door Pippi Door1)")
    for arg in call.args:
        if arg.startswith("?"):
            raise error(f"a goal names constants only, found the variable {arg}", node.span)
    return Goal(call=call, span=span)
