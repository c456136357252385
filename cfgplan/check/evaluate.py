"""The safe Lisp subset of ``(eval EXPR)`` preconditions (thesis Appendix A).

EXPR is interpreted here, never handed to Python's or Lisp's ``eval``. The
subset: ``quote``, ``not``, ``and``, ``or``, ``eql``/``eq``/``equal``, ``=``,
``<``, ``>``, ``<=``, ``>=``, ``+``, ``-``; the constants ``t`` and ``nil``;
numbers; and variables (``?r``), which evaluate to what they are bound to.
Anything else is rejected by :func:`problems` at check time.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from itertools import pairwise

from cfgplan.ir.model import SExpr, is_variable
from cfgplan.notation import sexpr_text

Value = str | int | float | bool | list["Value"]

SPECIAL = ("quote", "and", "or")
FUNCTIONS: dict[str, tuple[int, int | None]] = {
    # name: (fewest arguments, most arguments or None for any)
    "not": (1, 1),
    "eql": (2, 2),
    "eq": (2, 2),
    "equal": (2, 2),
    "=": (1, None),
    "<": (1, None),
    ">": (1, None),
    "<=": (1, None),
    ">=": (1, None),
    "+": (0, None),
    "-": (1, None),
}
ALLOWED = (*SPECIAL, *FUNCTIONS)


class EvalFailure(Exception):
    """An expression could not be evaluated for these bindings (e.g. < on a symbol)."""


def problems(expr: SExpr) -> list[str]:
    """Why ``expr`` is outside the safe subset; empty if it is inside."""
    found: list[str] = []
    stack: list[SExpr] = [expr]
    while stack:
        item = stack.pop()
        if isinstance(item, list):
            if not item:
                continue
            head = item[0]
            if not isinstance(head, str) or head not in ALLOWED:
                shown = head if not isinstance(head, list) else "a list"
                found.append(f"eval may not call {shown}; it allows only " + ", ".join(ALLOWED))
                continue
            args = item[1:]
            if head == "quote":
                if len(args) != 1:
                    found.append("quote takes exactly one argument")
                continue
            if head in FUNCTIONS:
                low, high = FUNCTIONS[head]
                if len(args) < low or (high is not None and len(args) > high):
                    want = str(low) if low == high else f"at least {low}"
                    found.append(f"{head} takes {want} argument(s), found {len(args)}")
            stack.extend(args)
        elif isinstance(item, str) and not is_variable(item) and item.lower() not in ("t", "nil"):
            found.append(f"the bare symbol {item} has no value; write (quote {item})")
    return found


def _number(value: Value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise EvalFailure(f"{_show(value)} is not a number")
    return value


def _leaf(value: str | int | float) -> str:
    if value is True:
        return "t"
    if value is False:
        return "nil"
    return str(value)


def _show(value: Value) -> str:
    return sexpr_text(value, _leaf)


def _truthy(value: Value) -> bool:
    return not (value is False or value == [] or value == "nil")


def _literal(term: str) -> Value:
    """A bound value as eval sees it: numbers become numbers, symbols stay."""
    try:
        return int(term)
    except ValueError:
        pass
    try:
        return float(term)
    except ValueError:
        return term


def _quoted(expr: SExpr, bindings: Mapping[str, str]) -> Value:
    """A quoted datum, with bound variables replaced (as the thesis's planner does)."""
    if isinstance(expr, list):
        return [_quoted(e, bindings) for e in expr]
    if isinstance(expr, str) and is_variable(expr):
        if expr not in bindings:
            raise EvalFailure(f"{expr} is not bound")
        return _literal(bindings[expr])
    return expr


def _compare(op: Callable[[float, float], bool], values: list[Value]) -> bool:
    nums = [_number(v) for v in values]
    return all(op(a, b) for a, b in pairwise(nums))


def evaluate(expr: SExpr, bindings: Mapping[str, str]) -> Value:
    """Evaluate ``expr`` (already validated by :func:`problems`) under ``bindings``."""
    if isinstance(expr, bool):
        return expr
    if isinstance(expr, (int, float)):
        return expr
    if isinstance(expr, str):
        if is_variable(expr):
            if expr not in bindings:
                raise EvalFailure(f"{expr} is not bound")
            return _literal(bindings[expr])
        if expr.lower() == "t":
            return True
        if expr.lower() == "nil":
            return False
        raise EvalFailure(f"the bare symbol {expr} has no value")
    if not expr:
        return False
    head, *args = expr
    if head == "quote":
        return _quoted(args[0], bindings)
    if head == "and":
        result: Value = True
        for a in args:
            result = evaluate(a, bindings)
            if not _truthy(result):
                return False
        return result
    if head == "or":
        for a in args:
            result = evaluate(a, bindings)
            if _truthy(result):
                return result
        return False
    values = [evaluate(a, bindings) for a in args]
    if head == "not":
        return not _truthy(values[0])
    if head in ("eql", "eq", "equal"):
        return values[0] == values[1]
    if head == "=":
        return _compare(lambda a, b: a == b, values)
    if head == "<":
        return _compare(lambda a, b: a < b, values)
    if head == ">":
        return _compare(lambda a, b: a > b, values)
    if head == "<=":
        return _compare(lambda a, b: a <= b, values)
    if head == ">=":
        return _compare(lambda a, b: a >= b, values)
    if head == "+":
        return sum(_number(v) for v in values)
    if head == "-":
        nums = [_number(v) for v in values]
        return -nums[0] if len(nums) == 1 else nums[0] - sum(nums[1:])
    raise EvalFailure(f"eval may not call {head}")


def holds(expr: SExpr, bindings: Mapping[str, str]) -> bool:
    """True when ``expr`` evaluates to a true value; EvalFailure propagates."""
    return _truthy(evaluate(expr, bindings))
