"""Unification of flat atoms, for checking data descriptors statically (thesis 4.4, 4.5).

A call ``(measure-door ?r ?d)`` instantiates its schema's descriptors by binding
the schema's parameters to the call's arguments (4.5, step a). The checker asks
whether an instantiated descriptor *can* equal a channel's or port's data:
variables unify with anything, consistently; constants must be equal. The
schema's own variables are renamed apart from the caller's first.
"""

from __future__ import annotations

from collections.abc import Mapping

from cfgplan.ir.model import Atom, Term, is_variable

Subst = dict[Term, Term]
Signature = tuple[str, int]
"""Name and arity: what identifies a functionality or method (4.5)."""

_APART = "'"
"""Appended to a schema's variables to rename them apart; no symbol can hold it."""


def walk(term: Term, subst: Mapping[Term, Term]) -> Term:
    """What ``term`` stands for under ``subst`` (a variable or a constant)."""
    while is_variable(term) and term in subst:
        term = subst[term]
    return term


def unify_terms(a: Term, b: Term, subst: Subst) -> Subst | None:
    """Extend ``subst`` so that ``a`` and ``b`` are equal, or None if they cannot be."""
    a, b = walk(a, subst), walk(b, subst)
    if a == b:
        return subst
    if is_variable(a):
        return {**subst, a: b}
    if is_variable(b):
        return {**subst, b: a}
    return None


def unify(a: Atom, b: Atom, subst: Subst | None = None) -> Subst | None:
    """Most general unifier of two atoms extending ``subst``; predicate and arity must match."""
    if a.signature != b.signature:
        return None
    return _unify_args(a.args, b.args, dict(subst or {}))


def _unify_args(xs: tuple[Term, ...], ys: tuple[Term, ...], subst: Subst) -> Subst | None:
    """``subst`` extended so that the terms of ``xs`` and ``ys`` are pairwise
    equal (as many of each), or None if they cannot be."""
    result: Subst | None = subst
    for x, y in zip(xs, ys, strict=True):
        if result is None:
            return None
        result = unify_terms(x, y, result)
    return result


def _apart(args: tuple[Term, ...]) -> tuple[Term, ...]:
    """A schema's terms, every variable renamed so it shares none with a caller."""
    return tuple(t + _APART if is_variable(t) else t for t in args)


def match(schema: Atom, call: Atom, descriptor: Atom, data: Atom) -> Subst | None:
    """How ``descriptor`` of the schema named ``schema``, called as ``call``, can be
    ``data``: a unifier, or None if it cannot. The schema's variables are
    renamed apart first; its terms are unified as they are, no atom is
    copied (the checker asks this of every body item's channels and ports:
    copies were a third of checking a 200-level chain)."""
    if schema.signature != call.signature or descriptor.signature != data.signature:
        return None
    subst = _unify_args(_apart(schema.args), call.args, {})
    if subst is None:
        return None
    return _unify_args(_apart(descriptor.args), data.args, subst)


def caller_equations(subst: Subst) -> list[tuple[Term, Term]]:
    """What a unifier from :func:`match` demands of the caller's own terms, e.g.
    ``[("?rh1", "?r")]``: a match that needs any is a coincidence of bindings."""
    return [(k, walk(k, subst)) for k in subst if not k.endswith(_APART)]


def instantiate(schema: Atom, call: Atom, descriptor: Atom) -> Atom:
    """``descriptor`` with the schema's parameters replaced by the call's arguments
    (for messages; other variables stay as written)."""
    binding: dict[Term, Term] = {}
    for param, arg in zip(schema.args, call.args, strict=False):
        if is_variable(param) and param not in binding:
            binding[param] = arg
    args = tuple(binding.get(t, t) for t in descriptor.args)
    return descriptor.model_copy(update={"args": args})
