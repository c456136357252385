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


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Item:
    """A method or functionality instance waiting on the stack."""

    label: int
    call: Ground  # (name, *args)
    ancestors: frozenset[Ground]  # method instances above it: the recursion guard


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Channel:
    """A channel between two labels; resolved once both are functionalities."""

    kind: str
    robots: Ground
    source: int
    target: int
    data: Ground
    bandwidth: float | None


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
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


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
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
    robots: frozenset[str]  # where the placed functionalities run
    resolved: frozenset[ChannelKey]  # channels whose two ends are placed

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
        robots=frozenset(),
        resolved=frozenset(),
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


ChannelKey = tuple[str, int, int, Ground]
"""A resolved channel's identity: kind, sender label, receiver label, data."""


def _settle(
    channels: tuple[Channel, ...],
    located: dict[int, Placed],
    touching: list[int],
    resolved: frozenset[ChannelKey],
    task: Task,
) -> tuple[tuple[Channel, ...], float, frozenset[ChannelKey]] | Dead:
    """The channels at ``touching`` (indices) may just have got both ends
    placed: check their location, merge each with an identical channel already
    resolved (same kind, ends and data; the larger bandwidth is kept), and
    return the channels, the cost the newly resolved ones add, and the
    identities of all resolved channels."""
    if not touching:
        return channels, 0.0, resolved
    out = list(channels)
    new: set[ChannelKey] = set()
    dropped: list[int] = []
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
        ident = (ch.kind, ch.source, ch.target, ch.data)
        if ident not in resolved and ident not in new:
            new.add(ident)
            added += task.weights.global_ if ch.kind == "global" else task.weights.local
            continue
        # An identical channel is already there (rare): keep it, drop this one.
        j = next(
            j
            for j, c in enumerate(out)
            if j != i and j not in dropped and (c.kind, c.source, c.target, c.data) == ident
            and c.source in located and c.target in located
        )
        kept = out[j]
        if ch.bandwidth is not None and (kept.bandwidth is None or ch.bandwidth > kept.bandwidth):
            out[j] = replace(kept, bandwidth=ch.bandwidth)
        dropped.append(i)
    if dropped:
        out = [c for i, c in enumerate(out) if i not in dropped]
    return tuple(out), added, resolved | new if new else resolved


@dataclass(frozen=True, slots=True)
class Expansion:
    """A method version instantiated with one binding, labels as offsets from
    the first fresh label; the same for every node that expands it."""

    size: int
    channels: tuple[tuple[str, Ground, int, int, Ground, float | None], ...]
    body: tuple[Ground, ...]
    outputs: dict[Ground, tuple[int, float | None]]  # data -> (offset, bandwidth)
    inputs: dict[Ground, tuple[int, ...]]  # data -> offsets
    effects: tuple[tuple[bool, Ground], ...]


def instantiate(method: MethodSchema, env: Bindings, where: str) -> Expansion | Dead:
    """Instantiate a method version under ``env`` (step 3a of 4.5), once."""
    offset = {body_label: i for i, (body_label, _) in enumerate(method.body)}
    channels = []
    for spec in method.channels:
        data = _instantiate(spec.data, env, where)
        robots = _instantiate(("robots", *spec.robots), env, where)
        if isinstance(data, Dead):
            return data
        if isinstance(robots, Dead):
            return robots
        channels.append(
            (spec.kind, robots[1:], offset[spec.source], offset[spec.target], data, spec.bandwidth)
        )
    body = []
    for _, call in method.body:
        ground = _instantiate(call, env, where)
        if isinstance(ground, Dead):
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


def expand_method(
    node: Partial, item: Item, expansion: Expansion, where: str, span: Span | None, choice: int
) -> Partial | Dead:
    """Step 3 of 4.5: fresh labels, add the method's channels, push its body,
    and re-wire channels at the expanded instance through ``:in``/``:out``."""
    first = node.next_label
    block = [
        Channel(kind, robots, first + src, first + dst, data, bandwidth)
        for kind, robots, src, dst, data, bandwidth in expansion.channels
    ]
    rewired: list[Channel] = []
    expanded = item.label
    for ch in node.channels:
        if ch.source == expanded:
            port = expansion.outputs.get(ch.data)
            if port is None:
                return Dead(
                    where, f"no :out entry produces {show(ch.data)}", span, condition="information"
                )
            bandwidth = ch.bandwidth
            if bandwidth is None and ch.kind == "global":
                bandwidth = port[1]  # a global channel allocates the :out's bandwidth
            rewired.append(
                Channel(ch.kind, ch.robots, first + port[0], ch.target, ch.data, bandwidth)
            )
        elif ch.target == expanded:
            offsets = expansion.inputs.get(ch.data)
            if not offsets:
                return Dead(
                    where, f"no :in entry consumes {show(ch.data)}", span, condition="information"
                )
            rewired.extend(
                Channel(ch.kind, ch.robots, ch.source, first + k, ch.data, ch.bandwidth)
                for k in offsets
            )
        else:
            rewired.append(ch)
    ancestors = item.ancestors | {item.call}
    pushed = tuple(Item(first + i, call, ancestors) for i, call in enumerate(expansion.body))
    # Fresh labels are not placed yet: no channel got resolved, nothing to settle.
    return Partial(
        stack=(*pushed, *node.stack[1:]),
        placed=node.placed,
        labels=node.labels,
        located=node.located,
        channels=(*block, *rewired),
        effects=(*node.effects, *expansion.effects) if expansion.effects else node.effects,
        next_label=first + expansion.size,
        path=(*node.path, choice),
        cost=node.cost,
        robots=node.robots,
        resolved=node.resolved,
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
        relabelled = list(node.channels)
        touching = []
        for i, ch in enumerate(relabelled):
            if ch.source == old or ch.target == old:
                touching.append(i)
                relabelled[i] = Channel(
                    ch.kind,
                    ch.robots,
                    existing if ch.source == old else ch.source,
                    existing if ch.target == old else ch.target,
                    ch.data,
                    ch.bandwidth,
                )
        settled = _settle(tuple(relabelled), node.located, touching, node.resolved, task)
        if isinstance(settled, Dead):
            return settled
        return Partial(
            stack=node.stack[1:],
            placed=node.placed,
            labels=node.labels,
            located=node.located,
            channels=settled[0],
            effects=node.effects,
            next_label=node.next_label,
            path=path,
            cost=node.cost + settled[1],
            robots=node.robots,
            resolved=settled[2],
        )
    assert env is not None
    io = task.io.get(item.call)
    if io is None:
        io = task.io[item.call] = (
            tuple(substitute(i, env) for i in schema.inputs),
            tuple(substitute(o, env) for o in schema.outputs),
        )
    new = Placed(item.label, item.call, schema, item.call[1], *io)
    located = dict(node.located)
    located[item.label] = new
    touching = _touching(node.channels, item.label)
    settled = _settle(node.channels, located, touching, node.resolved, task)
    if isinstance(settled, Dead):
        return settled
    w = task.weights
    added = settled[1] + (schema.cost if schema.cost is not None else w.functionality)
    robots = node.robots
    if new.robot not in robots:
        added += w.robot
        robots = robots | {new.robot}
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
        robots=robots,
        resolved=settled[2],
    )


def canonical(node: Partial) -> object:
    """The node up to labels: placed instances, channels, stack and P. Two nodes
    with the same canonical form have the same completions (up to labels)."""
    names: dict[int, object] = {p.label: p.call for p in node.placed}
    for index, item in enumerate(node.stack):
        names[item.label] = index
    channels = frozenset(
        (ch.kind, ch.robots, names[ch.source], names[ch.target], ch.data, ch.bandwidth)
        for ch in node.channels
    )
    stack = tuple((item.call, item.ancestors) for item in node.stack)
    placed = frozenset(p.call for p in node.placed)
    return placed, channels, stack, frozenset(node.effects)
