"""A partial configuration: the search node of the planner (thesis 4.5).

It holds the method stack, the functionalities added so far (C), the channels
(Ch), the collected postconditions (P) and the label counter. Every operation
returns a new node or a :class:`Dead` end with its reason; nodes are never
mutated once built, so the search can keep many of them.

Labels: the goal is label 1 and every instance a method body creates takes
the next number, in body order, when the method is expanded. A reused
functionality keeps the label of its first instance.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from cfgplan.ir.model import Span
from cfgplan.planner.match import Bindings, substitute
from cfgplan.planner.task import FunctionalitySchema, Ground, MethodSchema, Task, show

Key = Ground
"""A functionality instance's identity: ``("camera", "Emil")``."""


@dataclass(frozen=True, slots=True)
class Item:
    """A method or functionality instance waiting on the stack."""

    label: int
    call: Ground  # (name, *args)
    ancestors: frozenset[Ground]  # method instances above it: the recursion guard


@dataclass(frozen=True, slots=True)
class Channel:
    """A channel between two labels; resolved once both are functionalities."""

    kind: str
    robots: Ground
    source: int
    target: int
    data: Ground
    bandwidth: float | None


@dataclass(frozen=True, slots=True)
class Placed:
    """A functionality instance in the configuration, located at ``robot``
    (its first argument), with its inputs and outputs instantiated."""

    label: int
    call: Key
    schema: FunctionalitySchema
    robot: str
    inputs: tuple[Ground, ...]
    outputs: tuple[Ground, ...]


@dataclass(frozen=True, slots=True)
class Dead:
    """Why a branch ended: shown by ``--verbose`` and when nothing is admissible."""

    where: str
    reason: str
    span: Span | None = None
    condition: str = "causal"


@dataclass(frozen=True, slots=True)
class Partial:
    """A node of the search: a configuration under construction."""

    stack: tuple[Item, ...]
    placed: tuple[Placed, ...]  # in the order added
    labels: dict[Key, int]  # functionality instance -> its label
    located: dict[int, Placed]  # label -> placed functionality
    channels: tuple[Channel, ...]  # in the thesis's list order (newest block first)
    effects: tuple[tuple[bool, Ground], ...]
    next_label: int
    path: tuple[int, ...]  # the choices made: orders equal costs as the thesis does
    cost: float  # of the settled part; see the module docstring of search.py

    @property
    def done(self) -> bool:
        return not self.stack


def root(goal: Ground) -> Partial:
    """The initial node: the goal alone on the stack, C empty."""
    return Partial(
        stack=(Item(1, goal, frozenset()),),
        placed=(),
        labels={},
        located={},
        channels=(),
        effects=(),
        next_label=2,
        path=(),
        cost=0.0,
    )


def describe_call(call: Ground) -> str:
    """``get-door-info(Pippi, Door1)``, as the thesis writes instances."""
    return f"{call[0]}({', '.join(call[1:])})"


def _instantiate(p: Ground, env: Bindings, where: str) -> Ground | Dead:
    ground = substitute(p, env)
    for term in ground[1:]:
        if term[:1] == "?":
            return Dead(where, f"{term} in {show(p)} is bound by nothing", condition="binding")
    return ground


def _touching(channels: tuple[Channel, ...], label: int) -> list[int]:
    return [i for i, ch in enumerate(channels) if ch.source == label or ch.target == label]


def _settle(
    channels: tuple[Channel, ...], located: dict[int, Placed], touching: list[int], task: Task
) -> tuple[tuple[Channel, ...], float] | Dead:
    """The channels at ``touching`` (indices) may just have got both ends
    placed: check their location, merge each with an identical channel already
    resolved (same kind, ends and data; the larger bandwidth is kept), and
    return the cost the newly resolved ones add."""
    if not touching:
        return channels, 0.0
    out = list(channels)
    existing: dict[tuple[str, int, int, Ground], int] | None = None
    dropped: set[int] = set()
    added = 0.0
    for i in touching:
        ch = channels[i]
        src, dst = located.get(ch.source), located.get(ch.target)
        if src is None or dst is None:
            continue
        wanted = (ch.robots[0], ch.robots[0]) if ch.kind == "local" else ch.robots
        if (src.robot, dst.robot) != wanted:
            return Dead(
                f"{ch.kind} channel {show(ch.data)}",
                f"declared ({ch.kind} {' '.join(ch.robots)}) but it runs from "
                f"{describe_call(src.call)} on {src.robot} to "
                f"{describe_call(dst.call)} on {dst.robot}",
                condition="location",
            )
        if existing is None:
            existing = {
                (c.kind, c.source, c.target, c.data): j
                for j, c in enumerate(channels)
                if j not in touching and c.source in located and c.target in located
            }
        ident = (ch.kind, ch.source, ch.target, ch.data)
        j = existing.get(ident)
        if j is None:
            existing[ident] = i
            added += task.weights.global_ if ch.kind == "global" else task.weights.local
            continue
        kept = out[j]
        if ch.bandwidth is not None and (kept.bandwidth is None or ch.bandwidth > kept.bandwidth):
            out[j] = replace(kept, bandwidth=ch.bandwidth)
        dropped.add(i)
    if dropped:
        out = [c for i, c in enumerate(out) if i not in dropped]
    return tuple(out), added


def expand_method(
    node: Partial, item: Item, method: MethodSchema, env: Bindings, choice: int
) -> Partial | Dead:
    """Step 3 of 4.5: fresh labels, add the method's channels, push its body,
    and re-wire channels at the expanded instance through ``:in``/``:out``."""
    where = f"{describe_call(item.call)}, version {method.version}"
    fresh: dict[str, int] = {}
    label = node.next_label
    for body_label, _ in method.body:
        fresh[body_label] = label
        label += 1
    block: list[Channel] = []
    for spec in method.channels:
        data = _instantiate(spec.data, env, where)
        robots = _instantiate(("robots", *spec.robots), env, where)
        if isinstance(data, Dead):
            return data
        if isinstance(robots, Dead):
            return robots
        block.append(
            Channel(
                spec.kind, robots[1:], fresh[spec.source], fresh[spec.target], data, spec.bandwidth
            )
        )
    rewired: list[Channel] = []
    for ch in node.channels:
        if ch.source == item.label:
            port = next((p for p in method.outputs if substitute(p.data, env) == ch.data), None)
            if port is None:
                return Dead(
                    where,
                    f"no :out entry produces {show(ch.data)}",
                    method.span,
                    condition="information",
                )
            bandwidth = ch.bandwidth
            if bandwidth is None and ch.kind == "global":
                bandwidth = port.bandwidth  # a global channel allocates the :out's bandwidth
            rewired.append(replace(ch, source=fresh[port.label], bandwidth=bandwidth))
        elif ch.target == item.label:
            ports = [p for p in method.inputs if substitute(p.data, env) == ch.data]
            if not ports:
                return Dead(
                    where,
                    f"no :in entry consumes {show(ch.data)}",
                    method.span,
                    condition="information",
                )
            rewired.extend(replace(ch, target=fresh[p.label]) for p in ports)
        else:
            rewired.append(ch)
    ancestors = item.ancestors | {item.call}
    pushed: list[Item] = []
    for body_label, call in method.body:
        ground = _instantiate(call, env, where)
        if isinstance(ground, Dead):
            return ground
        pushed.append(Item(fresh[body_label], ground, ancestors))
    effects = list(node.effects)
    for eff in method.effects:
        effects.append((eff.positive, substitute(eff.pattern, env)))
    # Fresh labels are not placed yet: no channel got resolved, nothing to settle.
    return Partial(
        stack=(*pushed, *node.stack[1:]),
        placed=node.placed,
        labels=node.labels,
        located=node.located,
        channels=(*block, *rewired),
        effects=tuple(effects),
        next_label=label,
        path=(*node.path, choice),
        cost=node.cost,
    )


def place_functionality(
    node: Partial,
    item: Item,
    schema: FunctionalitySchema,
    env: Bindings | None,
    choice: int | None,
    task: Task,
) -> Partial | Dead:
    """Step 2a of 4.5: add the functionality to C, or reuse the instance already
    there (its channels move to the existing label). ``env`` binds its
    preconditions (None when it is reused)."""
    existing = node.labels.get(item.call)
    path = node.path if choice is None else (*node.path, choice)
    if existing is not None:
        old = item.label
        channels = tuple(
            ch
            if ch.source != old and ch.target != old
            else replace(
                ch,
                source=existing if ch.source == old else ch.source,
                target=existing if ch.target == old else ch.target,
            )
            for ch in node.channels
        )
        settled = _settle(channels, node.located, _touching(node.channels, old), task)
        if isinstance(settled, Dead):
            return settled
        return replace(
            node, stack=node.stack[1:], channels=settled[0], path=path, cost=node.cost + settled[1]
        )
    assert env is not None
    args = env  # the name's bindings extended by the preconditions'
    new = Placed(
        item.label,
        item.call,
        schema,
        item.call[1],
        tuple(substitute(i, args) for i in schema.inputs),
        tuple(substitute(o, args) for o in schema.outputs),
    )
    located = dict(node.located)
    located[item.label] = new
    settled = _settle(node.channels, located, _touching(node.channels, item.label), task)
    if isinstance(settled, Dead):
        return settled
    w = task.weights
    added = settled[1] + (schema.cost if schema.cost is not None else w.functionality)
    if all(p.robot != new.robot for p in node.placed):
        added += w.robot
    effects = list(node.effects)
    for eff in schema.effects:
        effects.append((eff.positive, substitute(eff.pattern, env)))
    labels = dict(node.labels)
    labels[item.call] = item.label
    return Partial(
        stack=node.stack[1:],
        placed=(*node.placed, new),
        labels=labels,
        located=located,
        channels=settled[0],
        effects=tuple(effects),
        next_label=node.next_label,
        path=path,
        cost=node.cost + added,
    )
