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
    """A functionality instance in the configuration, located at ``call[1]``."""

    label: int
    call: Key
    schema: FunctionalitySchema

    @property
    def robot(self) -> str:
        return self.call[1]


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
    channels: tuple[Channel, ...]  # in the thesis's list order (newest block first)
    effects: tuple[tuple[bool, Ground], ...]
    next_label: int
    path: tuple[int, ...]  # the choices made: orders equal costs as the thesis does

    @property
    def done(self) -> bool:
        return not self.stack

    def located(self) -> dict[int, Placed]:
        return {p.label: p for p in self.placed}


def root(goal: Ground) -> Partial:
    """The initial node: the goal alone on the stack, C empty."""
    return Partial(
        stack=(Item(1, goal, frozenset()),),
        placed=(),
        labels={},
        channels=(),
        effects=(),
        next_label=2,
        path=(),
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


def _settle_channels(
    channels: list[Channel], located: dict[int, Placed]
) -> tuple[Channel, ...] | Dead:
    """Check the location of every resolved channel and merge identical ones
    (same kind, ends and data; the larger bandwidth is kept)."""
    out: list[Channel] = []
    seen: dict[tuple[str, int, int, Ground], int] = {}
    for ch in channels:
        src, dst = located.get(ch.source), located.get(ch.target)
        if src is not None and dst is not None:
            wanted = (ch.robots[0], ch.robots[0]) if ch.kind == "local" else ch.robots
            if (src.robot, dst.robot) != wanted:
                return Dead(
                    f"{ch.kind} channel {show(ch.data)}",
                    f"declared ({ch.kind} {' '.join(ch.robots)}) but it runs from "
                    f"{describe_call(src.call)} on {src.robot} to "
                    f"{describe_call(dst.call)} on {dst.robot}",
                    condition="location",
                )
            ident = (ch.kind, ch.source, ch.target, ch.data)
            if ident in seen:
                index = seen[ident]
                kept = out[index]
                if ch.bandwidth is not None and (
                    kept.bandwidth is None or ch.bandwidth > kept.bandwidth
                ):
                    out[index] = replace(kept, bandwidth=ch.bandwidth)
                continue
            seen[ident] = len(out)
        out.append(ch)
    return tuple(out)


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
    channels = _settle_channels([*block, *rewired], node.located())
    if isinstance(channels, Dead):
        return channels
    return Partial(
        stack=(*pushed, *node.stack[1:]),
        placed=node.placed,
        labels=node.labels,
        channels=channels,
        effects=tuple(effects),
        next_label=label,
        path=(*node.path, choice),
    )


def place_functionality(
    node: Partial, item: Item, schema: FunctionalitySchema, env: Bindings | None, choice: int | None
) -> Partial | Dead:
    """Step 2a of 4.5: add the functionality to C, or reuse the instance already
    there (its channels move to the existing label). ``env`` binds its
    preconditions (None when it is reused)."""
    existing = node.labels.get(item.call)
    path = node.path if choice is None else (*node.path, choice)
    if existing is not None:
        channels = [
            replace(
                ch,
                source=existing if ch.source == item.label else ch.source,
                target=existing if ch.target == item.label else ch.target,
            )
            for ch in node.channels
        ]
        settled = _settle_channels(channels, node.located())
        if isinstance(settled, Dead):
            return settled
        return replace(node, stack=node.stack[1:], channels=settled, path=path)
    assert env is not None
    placed = (*node.placed, Placed(item.label, item.call, schema))
    located = {p.label: p for p in placed}
    settled = _settle_channels(list(node.channels), located)
    if isinstance(settled, Dead):
        return settled
    effects = list(node.effects)
    for eff in schema.effects:
        effects.append((eff.positive, substitute(eff.pattern, env)))
    labels = dict(node.labels)
    labels[item.call] = item.label
    return Partial(
        stack=node.stack[1:],
        placed=placed,
        labels=labels,
        channels=settled,
        effects=tuple(effects),
        next_label=node.next_label,
        path=path,
    )


def cost(node: Partial, task: Task) -> float:
    """Cost of the settled part (3.5): functionalities placed, their locations,
    and channels whose both ends are placed. It never decreases as a node
    grows, and equals the configuration's cost once the stack is empty."""
    w = task.weights
    located = node.located()
    robots = {p.robot for p in node.placed}
    total = w.robot * len(robots)
    for p in node.placed:
        total += p.schema.cost if p.schema.cost is not None else w.functionality
    for ch in node.channels:
        if ch.source in located and ch.target in located:
            total += w.global_ if ch.kind == "global" else w.local
    return total
