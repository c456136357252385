"""Substitution and matching of flat atoms (thesis 4.5, steps 2b and 3a).

Atoms and calls are tuples ``(name, *args)``; a term starting with ``?`` is a
variable. These are the primitive operations the matcher (:mod:`match`), the
expansion step (:mod:`partial`) and the bound (:mod:`bound`) build on.
"""

from __future__ import annotations

from collections.abc import Mapping

from cfgplan.planner.task import Ground, Pattern

Bindings = dict[str, str]
"""Variable -> symbol."""


def is_var(term: str) -> bool:
    return term[:1] == "?"


def substitute(p: Pattern, env: Mapping[str, str]) -> Ground:
    """Replace bound variables of ``p`` (unbound ones stay as they are)."""
    return tuple(env.get(t, t) if t[:1] == "?" else t for t in p)


def is_ground(p: Pattern) -> bool:
    """No variable among the arguments (the name is never one)."""
    return not any(t[:1] == "?" for t in p[1:])


def unify(p: Pattern, fact: Ground, env: Bindings) -> Bindings | None:
    """Extend ``env`` so that ``p`` equals ``fact`` (same predicate and arity
    assumed), or None. Returns ``env`` itself when nothing new is bound."""
    new: Bindings | None = None
    for term, value in zip(p[1:], fact[1:], strict=True):
        if term[:1] == "?":
            bound = env.get(term) if new is None else new.get(term)
            if bound is None:
                if new is None:
                    new = dict(env)
                new[term] = value
            elif bound != value:
                return None
        elif term != value:
            return None
    return new if new is not None else env


def bind_name(params: Pattern, args: Ground) -> Bindings | None:
    """Match a schema's name parameters against a call's arguments: a variable
    binds (a repeated one must get the same value), a constant must be equal."""
    env: Bindings = {}
    for param, arg in zip(params, args, strict=True):
        if param[:1] == "?":
            if env.setdefault(param, arg) != arg:
                return None
        elif param != arg:
            return None
    return env
