"""The step of the planner (thesis 4.5): the children of a partial configuration.

:func:`successors` takes the item on top of the stack and yields what 4.5 does
with it, in the thesis's order:

- a method instance (step 2b, 3): one child per version (domain order) and per
  binding of its preconditions (state order): the backtrack points;
- a functionality instance (step 2a): reused if it already exists in C, else
  added, once per binding of its own preconditions (several bindings branch
  like a method's: they may give different outputs or postconditions).

Each branch that cannot go on is yielded as a :class:`DeadEnd` with its
reason. The best-first search, the greedy dive and the naive baseline
(``benchmarks/naive.py``) all grow nodes with this one function.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

from cfgplan.notation import call_text
from cfgplan.planner.ground import Grounder
from cfgplan.planner.match import why_not
from cfgplan.planner.partial import (
    Item,
    Partial,
    expand_method,
    place_functionality,
    reuse_functionality,
)
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import FunctionalitySchema, Ground, MethodSchema
from cfgplan.planner.unify import bind_name

if TYPE_CHECKING:
    from cfgplan.planner.replay import Replays

Child = Partial | DeadEnd


def successors(
    grounder: Grounder, node: Partial, remember: Replays | None = None
) -> Iterator[Child]:
    """The children of ``node`` (whose stack is not empty), in 4.5's order;
    ``remember``: the search's replay rules, which give each child its
    memory (:mod:`cfgplan.planner.replay`; None: none is kept)."""
    item = node.stack[0]
    versions = grounder.task.versions(item.call)
    if versions:
        yield from _expand(grounder, node, item, versions, remember)
    else:
        yield from _place(grounder, node, item, remember)


def _expand(
    grounder: Grounder,
    node: Partial,
    item: Item,
    versions: tuple[MethodSchema, ...],
    remember: Replays | None,
) -> Iterator[Child]:
    if item.call in item.ancestors:
        yield DeadEnd(
            call_text(item.call),
            "it recurs on its own expansion path",
            condition=Condition.RECURSION,
        )
        return
    choice = 0
    for method in versions:
        options = grounder.expansions(method, item.call)
        if not options:
            where = f"{call_text(item.call)}, version {method.version}"
            yield _no_binding(grounder, method, item.call, where)
            continue
        for expansion in options:
            if isinstance(expansion, DeadEnd):
                yield expansion
            else:
                memory = (
                    None if remember is None else remember.expanding(node, item, expansion, choice)
                )
                yield expand_method(node, item, expansion, method.span, choice, memory)
            choice += 1


def _place(
    grounder: Grounder, node: Partial, item: Item, remember: Replays | None
) -> Iterator[Child]:
    task = grounder.task
    schema = task.functionality(item.call)
    if schema is None:
        yield DeadEnd(
            call_text(item.call),
            "is neither a method nor a functionality",
            condition=Condition.DOMAIN,
        )
        return
    existing = node.labels.get(item.call)
    if existing is not None:
        memory = None if remember is None else remember.placing(node, False)
        yield reuse_functionality(node, item, existing, task, memory)
        return
    options = grounder.instances(schema, item.call)
    if not options:
        yield _no_binding(grounder, schema, item.call, call_text(item.call))
        return
    memory = None if remember is None else remember.placing(node, len(options) > 1)
    for index, instance in enumerate(options):
        choice = index if len(options) > 1 else None
        yield place_functionality(node, item, schema, instance, choice, task, memory)


def _no_binding(
    grounder: Grounder, schema: MethodSchema | FunctionalitySchema, call: Ground, where: str
) -> DeadEnd:
    """Why a schema does not apply to ``call``: its name does not match, or the
    first precondition no binding got past."""
    env = bind_name(schema.params, call[1:])
    if env is None:
        if isinstance(schema, MethodSchema):
            reason = f"its name ({schema.name} {' '.join(schema.params)}) does not match"
            return DeadEnd(where, reason, schema.span, Condition.BINDING)
        reason = f"does not match the functionality ({schema.name} {' '.join(schema.params)})"
        return DeadEnd(where, reason, schema.span, Condition.DOMAIN)
    failure = grounder.failure(
        schema, call, lambda: why_not(grounder.task, schema.tests, env, schema.params)
    )
    return DeadEnd(
        where,
        failure.describe(),
        failure.span or schema.span,
        Condition.PRECONDITION,
        failure.condition,
        failure.bindings,
    )
