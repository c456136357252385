"""Ground instances of the domain's schemas, made on demand and remembered.

The planner grounds lazily (pyperplan grounds everything up front; here the
method hierarchy decides what is reachable). What it grounds depends only on
the task, so it is computed once per task and shared by every search of it:

- the bindings of a schema's preconditions for a call (4.5, step 2b);
- a method version instantiated under one binding: its :class:`Expansion`
  with labels as offsets (4.5, step 3a);
- a functionality's inputs, outputs and postconditions under one binding.

Each memo is keyed by everything its value depends on: the schema (name,
arity and version), and the call or the complete binding.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from cfgplan.notation import atom_text
from cfgplan.planner.match import Failure, bindings
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import (
    FunctionalitySchema,
    Ground,
    MethodSchema,
    Pattern,
    Signature,
    Task,
    Test,
)
from cfgplan.planner.unify import Bindings, bind_name, is_ground, key, substitute

Effects = tuple[tuple[bool, Ground], ...]
"""Postconditions P: (positive, atom); ``(not ATOM)`` is ``(False, atom)``."""

IO = tuple[tuple[Ground, ...], tuple[Ground, ...]]
"""A functionality instance's inputs and outputs."""

ChannelSpec = tuple[str, Ground, int, int, Ground, float | None]
"""(kind, robots, source offset, target offset, data, bandwidth)."""

BindingKey = tuple[tuple[str, str], ...]
"""Bindings in a hashable form: :func:`cfgplan.planner.unify.key`."""


@dataclass(frozen=True, slots=True)
class Expansion:
    """A method version instantiated with one binding, labels as offsets from
    the first fresh label; the same for every node that expands it."""

    size: int
    channels: tuple[ChannelSpec, ...]
    body: tuple[Ground, ...]
    outputs: dict[Ground, tuple[int, float | None]]  # data -> (offset, bandwidth)
    inputs: dict[Ground, tuple[int, ...]]  # data -> offsets
    effects: Effects


@dataclass(frozen=True, slots=True)
class FunctionalityInstance:
    """A functionality call under one binding of its preconditions."""

    io: IO
    effects: Effects


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


def instantiate(method: MethodSchema, env: Bindings, where: str) -> Expansion | DeadEnd:
    """Instantiate a method version under ``env`` (step 3a of 4.5)."""
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
    return Expansion(len(method.body), tuple(channels), tuple(body), outputs, inputs, effects)


@dataclass
class Grounder:
    """The memo of ground instances for one task."""

    task: Task
    _method_bindings: dict[tuple[Ground, int], tuple[Bindings, ...]] = field(
        default_factory=dict
    )
    _functionality_bindings: dict[Ground, tuple[Bindings, ...]] = field(default_factory=dict)
    _expansions: dict[tuple[Signature, int, BindingKey], Expansion | DeadEnd] = field(
        default_factory=dict
    )
    _instances: dict[tuple[Signature, BindingKey], FunctionalityInstance] = field(
        default_factory=dict
    )
    _failures: dict[tuple[Signature, int, Ground], Failure] = field(default_factory=dict)

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

    def expansion(self, method: MethodSchema, env: Bindings, where: str) -> Expansion | DeadEnd:
        """``method`` instantiated under ``env``, made once."""
        memo = ((method.name, len(method.params)), method.version, key(env))
        found = self._expansions.get(memo)
        if found is None:
            found = self._expansions[memo] = instantiate(method, env, where)
        return found

    def instance(self, schema: FunctionalitySchema, env: Bindings) -> FunctionalityInstance:
        """The inputs, outputs and postconditions of a functionality under one
        binding of its preconditions: they may use variables the preconditions
        bind (``(loc ?r) :precond ((in ?r ?room)) :out ((pos ?r ?room))``)."""
        memo = ((schema.name, len(schema.params)), key(env))
        found = self._instances.get(memo)
        if found is None:
            io = (
                tuple(substitute(i, env) for i in schema.inputs),
                tuple(substitute(o, env) for o in schema.outputs),
            )
            effects = tuple((e.positive, substitute(e.pattern, env)) for e in schema.effects)
            found = self._instances[memo] = FunctionalityInstance(io, effects)
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
