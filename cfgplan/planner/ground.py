"""Ground instances of the domain's schemas, made on demand and remembered.

The planner grounds lazily (pyperplan grounds everything up front; here the
method hierarchy decides what is reachable). What it grounds depends only on
the task, so it is computed once per task and shared by every search of it:

- the bindings of a schema's preconditions for a call (4.5, step 2b);
- a method version instantiated for a call under each binding: its
  :class:`Expansion` with labels as offsets (4.5, step 3a);
- a functionality call's inputs, outputs and postconditions under each binding.

Each memo is keyed by everything its value depends on: the call (which names
the schema: name and arity) and, for a method, the version.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

from cfgplan.notation import atom_text, call_text
from cfgplan.planner.match import Failure, bindings, exists
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.senders import Placement
from cfgplan.planner.task import (
    FunctionalitySchema,
    Ground,
    MethodSchema,
    Pattern,
    Signature,
    Task,
    Test,
)
from cfgplan.planner.unify import Bindings, bind_name, is_ground, substitute

Effects = tuple[tuple[bool, Ground], ...]
"""Postconditions P: (positive, atom); ``(not ATOM)`` is ``(False, atom)``."""

IO = tuple[tuple[Ground, ...], tuple[Ground, ...]]
"""A functionality instance's inputs and outputs."""

ChannelSpec = tuple[str, Ground, int, int, Ground, float | None]
"""(kind, robots, source offset, target offset, data, bandwidth)."""


class Expansion(NamedTuple):
    """A method version instantiated with one binding, labels as offsets from
    the first fresh label; the same for every node that expands it.

    It carries the numbers the canonical form names what it creates by
    (:mod:`cfgplan.planner.canonical`), so that items and channels are
    numbered when they are made, never afterwards: each channel's kind, robots,
    data and bandwidth, and each body item's call with no recursive ancestor
    (an item below a recursive method is numbered with those ancestors by
    :func:`~cfgplan.planner.canonical.canonical`). ``number`` numbers a
    channel whose bandwidth its re-wiring sets."""

    size: int
    channels: tuple[ChannelSpec, ...]
    body: tuple[Ground, ...]
    outputs: dict[Ground, tuple[int, float | None]]  # data -> (offset, bandwidth)
    inputs: dict[Ground, tuple[int, ...]]  # data -> offsets
    effects: Effects
    where: str = ""  # "CALL, version N": where a dead end met expanding it is
    channel_numbers: tuple[int, ...] = ()  # per channel: (kind, robots, data, bandwidth), numbered
    body_numbers: tuple[int, ...] = ()  # per body item: (call, frozenset()), numbered
    recursive: bool = False  # the method can recur: it is a relevant ancestor of its body
    number: Numbering | None = None  # the numbering all of these come from


class FunctionalityInstance(NamedTuple):
    """A functionality call under one binding of its preconditions, with the
    numbers canonical forms name it by (:class:`Numbering`): ``number`` for
    the call with its inputs and outputs, ``name`` for the call alone."""

    io: IO
    effects: Effects
    number: int
    name: int


def _instance(
    schema: FunctionalitySchema, call: Ground, env: Bindings, number: Numbering
) -> FunctionalityInstance:
    io = (
        tuple(substitute(i, env) for i in schema.inputs),
        tuple(substitute(o, env) for o in schema.outputs),
    )
    effects = tuple((e.positive, substitute(e.pattern, env)) for e in schema.effects)
    return FunctionalityInstance(io, effects, number((call, *io)), number(call))


def _ground(p: Pattern, env: Bindings, where: str) -> Ground | DeadEnd:
    ground = substitute(p, env)
    if not is_ground(ground):
        free = next(t for t in ground[1:] if t[:1] == "?")
        return DeadEnd(
            where, f"{free} in {atom_text(p)} is bound by nothing", None, Condition.BINDING
        )
    return ground


def channel_kind(declared: str, robots: Ground) -> tuple[str, Ground]:
    """What a channel is once its robots are known: ``(any A B)`` is
    ``(local A)`` when A is B and ``(global A B)`` otherwise (an extension
    beyond the thesis); ``local`` and ``global`` stay what they say, so a
    declared global channel between ends on one robot stays global (6.4's 53)."""
    if declared != "any":
        return declared, robots
    return ("local", robots[:1]) if robots[0] == robots[1] else ("global", robots)


def instantiate(
    method: MethodSchema, env: Bindings, where: str, number: Numbering, recursive: bool
) -> Expansion | DeadEnd:
    """Instantiate a method version under ``env`` (step 3a of 4.5), numbered
    by ``number``; ``recursive``: whether the method's signature can recur
    (:attr:`Task.recursive`)."""
    offset = {body_label: i for i, (body_label, _) in enumerate(method.body)}
    channels: list[ChannelSpec] = []
    for spec in method.channels:
        data = _ground(spec.data, env, where)
        if isinstance(data, DeadEnd):
            return data
        robots = _ground(("robots", *spec.robots), env, where)
        if isinstance(robots, DeadEnd):
            return robots
        kind, ends = channel_kind(spec.kind, robots[1:])
        channels.append(
            (kind, ends, offset[spec.source], offset[spec.target], data, spec.bandwidth)
        )
    body = []
    for _, call in method.body:
        ground = _ground(call, env, where)
        if isinstance(ground, DeadEnd):
            return ground
        body.append(ground)
    outputs: dict[Ground, tuple[int, float | None]] = {}
    for port in method.outputs:
        outputs.setdefault(substitute(port.data, env), (offset[port.label], port.bandwidth))
    inputs: dict[Ground, tuple[int, ...]] = {}
    for port in method.inputs:
        data = substitute(port.data, env)
        inputs[data] = (*inputs.get(data, ()), offset[port.label])
    effects = tuple((eff.positive, substitute(eff.pattern, env)) for eff in method.effects)
    return Expansion(
        len(method.body),
        tuple(channels),
        tuple(body),
        outputs,
        inputs,
        effects,
        where,
        tuple(number((kind, ends, data, bw)) for kind, ends, _, _, data, bw in channels),
        tuple(number((call, frozenset())) for call in body),
        recursive,
        number,
    )


@dataclass(eq=False, repr=False)
class Grounder:
    """The memo of ground instances for one task."""

    task: Task
    _method_bindings: dict[tuple[Ground, int], tuple[Bindings, ...]] = field(default_factory=dict)
    _functionality_bindings: dict[Ground, tuple[Bindings, ...]] = field(default_factory=dict)
    _expansions: dict[tuple[Ground, int], tuple[Expansion | DeadEnd, ...]] = field(
        default_factory=dict
    )
    _raw: dict[tuple[Ground, int], tuple[Expansion | DeadEnd, ...]] = field(default_factory=dict)
    _instances: dict[Ground, tuple[FunctionalityInstance, ...]] = field(default_factory=dict)
    _failures: dict[tuple[Signature, int, Ground], Failure] = field(default_factory=dict)
    numbering: Numbering = field(default_factory=Numbering)
    """Numbers for the values of the task's search nodes (canonical forms, fingerprints)."""
    graphs: dict[bool, object] = field(default_factory=dict)
    """The AND/OR graphs of these expansions, one each way of noting the
    media: :func:`cfgplan.planner.graph.graph_of` makes and keeps them here,
    so that they go with the grounder (this module knows nothing of them)."""

    def method_bindings(self, method: MethodSchema, call: Ground) -> tuple[Bindings, ...]:
        """Every binding of a method version's preconditions for ``call``
        (none when its name does not match), facts in state order."""
        memo = (call, method.version)
        found = self._method_bindings.get(memo)
        if found is None:
            found = self._method_bindings[memo] = self._bindings(method.params, method.tests, call)
        return found

    def functionality_bindings(
        self, schema: FunctionalitySchema, call: Ground
    ) -> tuple[Bindings, ...]:
        """Every binding of a functionality's preconditions for ``call``."""
        found = self._functionality_bindings.get(call)
        if found is None:
            found = self._functionality_bindings[call] = self._bindings(
                schema.params, schema.tests, call
            )
        return found

    def _bindings(
        self, params: Pattern, tests: tuple[Test, ...], call: Ground
    ) -> tuple[Bindings, ...]:
        env = bind_name(params, call[1:])
        return () if env is None else tuple(bindings(self.task, tests, env))

    def expansions(self, method: MethodSchema, call: Ground) -> tuple[Expansion | DeadEnd, ...]:
        """A method version instantiated for ``call`` under each binding of its
        preconditions (state order), made once: the same for every node that
        expands ``call``, whatever its ancestors. An expansion that can never
        be placed (:mod:`cfgplan.planner.senders`: a channel whose sending end
        can never be on the robot it declares) is given as a dead end, in its
        place."""
        memo = (call, method.version)
        found = self._expansions.get(memo)
        if found is None:
            self.placement.senders(call)  # what is below call, analysed once
            found = self._expansions[memo] = tuple(
                self._placed(e) for e in self._instantiated(method, call)
            )
        return found

    def _placed(self, expansion: Expansion | DeadEnd) -> Expansion | DeadEnd:
        if isinstance(expansion, DeadEnd):
            return expansion
        dead = self.placement.misplaced(expansion)
        if dead is None:
            return expansion
        return DeadEnd(expansion.where, dead.describe(), condition=dead.condition)

    def _instantiated(self, method: MethodSchema, call: Ground) -> tuple[Expansion | DeadEnd, ...]:
        """:meth:`expansions` before :mod:`cfgplan.planner.senders` has its say."""
        memo = (call, method.version)
        found = self._raw.get(memo)
        if found is None:
            where = f"{call_text(call)}, version {method.version}"
            recursive = (method.name, len(method.params)) in self.task.recursive
            found = self._raw[memo] = tuple(
                instantiate(method, env, where, self.numbering, recursive)
                for env in self.method_bindings(method, call)
            )
        return found

    @cached_property
    def placement(self) -> Placement:
        """Where each method instance can send its outputs from (made once)."""
        task = self.task

        def every(call: Ground) -> Iterator[Expansion | DeadEnd]:
            for method in task.versions(call):
                yield from self._instantiated(method, call)

        known: dict[Ground, bool] = {}

        def placeable(call: Ground) -> bool:
            """Some binding of its preconditions exists (found, not all listed)."""
            found = known.get(call)
            if found is None:
                schema = task.functionality(call)
                env = None if schema is None else bind_name(schema.params, call[1:])
                found = known[call] = (
                    schema is not None and env is not None and exists(task, schema.tests, env)
                )
            return found

        return Placement(task, every, placeable)

    def instances(
        self, schema: FunctionalitySchema, call: Ground
    ) -> tuple[FunctionalityInstance, ...]:
        """The inputs, outputs and postconditions of a functionality call under
        each binding of its preconditions (state order), made once: they may
        use variables the preconditions bind (``(loc ?r) :precond ((in ?r
        ?room)) :out ((pos ?r ?room))``)."""
        found = self._instances.get(call)
        if found is None:
            found = self._instances[call] = tuple(
                _instance(schema, call, env, self.numbering)
                for env in self.functionality_bindings(schema, call)
            )
        return found

    def failure(
        self,
        schema: MethodSchema | FunctionalitySchema,
        call: Ground,
        explain: Callable[[], Failure],
    ) -> Failure:
        """Why ``schema`` has no binding for ``call``: ``explain()``, made once."""
        version = schema.version if isinstance(schema, MethodSchema) else 0
        memo = ((schema.name, len(schema.params)), version, call)
        found = self._failures.get(memo)
        if found is None:
            found = self._failures[memo] = explain()
        return found
