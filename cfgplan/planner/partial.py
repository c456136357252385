"""A partial configuration: the search node of the planner (thesis 4.5).

It holds the method stack, the functionalities added so far (C), the channels
(Ch), the collected postconditions (P) and the label counter. The two steps of
4.5 that grow it are here: :func:`expand_method` (step 3) and
:func:`place_functionality` / :func:`reuse_functionality` (step 2a). Every step
returns a new node or a :class:`DeadEnd` with its reason; nodes are never
mutated once built, so the search can keep many of them.

Labels: the goal is label 1 and every instance a method body creates takes
the next number, in body order, when the method is expanded. A reused
functionality keeps the label of its first instance.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from cfgplan.configuration.media import Demand, assign
from cfgplan.ir.model import Span
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.ground import Expansion, FunctionalityInstance
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import FunctionalitySchema, Ground, Task

if TYPE_CHECKING:
    from cfgplan.planner.replay import Memory

Key = Ground
"""A functionality instance's identity: ``("camera", "Emil")``."""

ChannelKey = tuple[str, int, int, Ground]
"""A resolved channel's identity: kind, sender label, receiver label, data."""


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Item:
    """A method or functionality instance waiting on the stack."""

    label: int
    call: Ground  # (name, *args)
    ancestors: frozenset[Ground]  # method instances above it: the recursion guard
    relevant: frozenset[Ground] = frozenset()  # its ancestors whose method can recur
    number: int = -1  # (call, relevant) numbered when made; -1: canonical() numbers it
    # (the root, and an item with relevant ancestors: numbering every child made costs more)


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Channel:
    """A channel between two labels; resolved once both are functionalities."""

    kind: str
    robots: Ground
    source: int
    target: int
    data: Ground
    bandwidth: float | None
    number: int = -1  # (kind, robots, data, bandwidth) numbered when made


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
    number: int  # its part of canonical(): FunctionalityInstance.number
    name: int  # its call, as canonical() names it: FunctionalityInstance.name


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
    cost: float  # of the settled part: placed functionalities, robots, resolved channels
    robots: frozenset[str]  # where the placed functionalities run
    resolved: frozenset[ChannelKey]  # channels whose two ends are placed
    memory: Memory | None = None
    """The sub-derivations it closed, for replays (:mod:`cfgplan.planner.replay`;
    None where the search does not replay)."""
    floor: float = 0.0
    """A lower bound on the cost of each of its derivations, known from an
    ancestor (a replay's deviations, :func:`cfgplan.planner.replay.deviations`)."""
    forbidden: tuple[tuple[int, ...], ...] = ()
    """Runs of choices it must not make next, to their end: the replays
    made beside an ancestor (:func:`cfgplan.planner.replay.filtered`)."""
    deviates: bool = False
    """It stands for a replayed node's other derivations: its top item is
    expanded step by step, not replayed again."""

    @property
    def done(self) -> bool:
        return not self.stack

    def but(self, **changes: Any) -> Partial:
        """A new node like this one but for ``changes`` (this one is kept as it is)."""
        return replace(self, **changes)


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


# -- step 3: expand a method ---------------------------------------------------------


def expand_method(
    node: Partial,
    item: Item,
    expansion: Expansion,
    span: Span | None,
    choice: int,
    memory: Memory | None = None,
) -> Partial | DeadEnd:
    """Step 3 of 4.5: fresh labels (a), add the method's channels (b), push its
    body (c), and re-wire every channel at the expanded instance through
    ``:out`` (its sending end) and ``:in`` (its receiving end) (d). A channel
    with *both* ends at the instance is re-wired at both; if that makes a
    functionality feed itself, the cycle check of step 4 rejects it.
    ``memory``: the child's (:meth:`cfgplan.planner.replay.Replays.expanding`;
    None where the search does not replay)."""
    first = node.next_label
    numbered = expansion.channel_numbers
    block = [
        Channel(kind, robots, first + src, first + dst, data, bandwidth, numbered[i])
        for i, (kind, robots, src, dst, data, bandwidth) in enumerate(expansion.channels)
    ]
    outputs, inputs = expansion.outputs, expansion.inputs

    def out(data: Ground) -> Port | None:
        port = outputs.get(data)
        return None if port is None else (first + port[0], port[1])

    def into(data: Ground) -> tuple[int, ...] | None:
        offsets = inputs.get(data)
        return tuple(first + k for k in offsets) if offsets else None

    done = rewire(node.channels, item.label, out, into, expansion.number)
    if isinstance(done, Unwired):
        verb = "produces" if done.end == ":out" else "consumes"
        missing = f"no {done.end} entry {verb} {atom_text(done.data)}"
        return DeadEnd(expansion.where, missing, span, Condition.INFORMATION)
    rewired = done[0]
    ancestors = item.ancestors | {item.call}
    # The body's relevant ancestors: the item's, and the item when its method
    # can recur; when every ancestor is one (a domain of one recursive
    # method, a conversion graph), they are the ancestors themselves, shared.
    relevant = item.relevant
    if expansion.recursive:
        relevant = ancestors if len(relevant) == len(item.ancestors) else relevant | {item.call}
    if relevant:  # numbered with them by canonical(): cheaper than numbering every child made
        pushed = tuple(
            [Item(first + i, call, ancestors, relevant) for i, call in enumerate(expansion.body)]
        )
    else:
        numbers = expansion.body_numbers
        pushed = tuple(
            [
                Item(first + i, call, ancestors, relevant, numbers[i])
                for i, call in enumerate(expansion.body)
            ]
        )
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
        memory=memory,
        floor=node.floor,
    )


Port = tuple[int, float | None]
"""Where a channel's sending end goes once re-wired: a label, and the bandwidth
of the ``:out`` entry it went through (None: it has none)."""


@dataclass(frozen=True, slots=True)
class Unwired:
    """A channel that cannot be re-wired: no ``end`` entry (``:out`` or ``:in``) for ``data``."""

    end: str
    data: Ground


def rewire(
    channels: Sequence[Channel],
    label: int,
    out: Callable[[Ground], Port | None],
    into: Callable[[Ground], Sequence[int] | None],
    number: Callable[[Hashable], int] | None,
) -> tuple[list[Channel], list[int]] | Unwired:
    """Step 3d of 4.5: every channel at ``label`` re-wired in place, its
    sending end through ``out`` (a global channel without a bandwidth takes
    the ``:out`` entry's, numbered by ``number``) and its receiving end
    through ``into`` (an ``:in`` may feed several: one channel each), both
    ends when it runs from the instance to itself. The channels, and the
    indices of those re-wired; or the first end that cannot be. One
    expansion's ports (:func:`expand_method`) or a replayed walk's, port
    after port (:func:`cfgplan.planner.replay.replay`)."""
    rewired: list[Channel] = []
    touching: list[int] = []
    for ch in channels:
        at_source, at_target = ch.source == label, ch.target == label
        if not (at_source or at_target):
            rewired.append(ch)
            continue
        source, bandwidth, numbered = ch.source, ch.bandwidth, ch.number
        if at_source:
            port = out(ch.data)
            if port is None:
                return Unwired(":out", ch.data)
            source = port[0]
            if bandwidth is None and ch.kind == "global" and port[1] is not None:
                bandwidth = port[1]  # a global channel allocates the :out's bandwidth
                assert number is not None  # the grounder numbers what it makes
                numbered = number((ch.kind, ch.robots, ch.data, bandwidth))
        targets: Sequence[int] = (ch.target,)
        if at_target:
            found = into(ch.data)
            if not found:
                return Unwired(":in", ch.data)
            targets = found
        for target in targets:
            touching.append(len(rewired))
            rewired.append(
                Channel(ch.kind, ch.robots, source, target, ch.data, bandwidth, numbered)
            )
    return rewired, touching


# -- step 2a: add a functionality, or reuse the one already in C ----------------------


def reuse_functionality(
    node: Partial, item: Item, existing: int, task: Task, memory: Memory | None = None
) -> Partial | DeadEnd:
    """Step 2a of 4.5 when the instance "already exists in the current
    configuration": it is not added again; the channels at the item's label
    move to the existing label (and may now have both ends placed)."""
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
                ch.number,
            )
    settled = settle(tuple(relabelled), node.located, touching, node.resolved, task)
    if isinstance(settled, DeadEnd):
        return settled
    channels, added, resolved = settled
    return Partial(
        stack=node.stack[1:],
        placed=node.placed,
        labels=node.labels,
        located=node.located,
        channels=channels,
        effects=node.effects,
        next_label=node.next_label,
        path=node.path,
        cost=node.cost + added,
        robots=node.robots,
        resolved=resolved,
        memory=memory,
        floor=node.floor,
    )


def place_functionality(
    node: Partial,
    item: Item,
    schema: FunctionalitySchema,
    instance: FunctionalityInstance,
    choice: int | None,
    task: Task,
    memory: Memory | None = None,
) -> Partial | DeadEnd:
    """Step 2a of 4.5: add the functionality to C at its robot (its first
    argument), with its inputs, outputs and postconditions instantiated under
    one binding of its preconditions (``instance``); ``choice`` is that
    binding's index when there are several."""
    inputs, outputs = instance.io
    new = Placed(
        item.label, item.call, schema, item.call[1], inputs, outputs, instance.number, instance.name
    )
    effects = instance.effects
    located = dict(node.located)
    located[item.label] = new
    label = item.label
    touching = [i for i, ch in enumerate(node.channels) if ch.source == label or ch.target == label]
    settled = settle(node.channels, located, touching, node.resolved, task)
    if isinstance(settled, DeadEnd):
        return settled
    channels, added, resolved = settled
    added += task.functionality_cost(schema, item.call)
    robots = node.robots
    if new.robot not in robots:
        added += task.agent_cost(new.robot)
        robots = robots | {new.robot}
    labels = dict(node.labels)
    labels[item.call] = item.label
    return Partial(
        stack=node.stack[1:],
        placed=(*node.placed, new),
        labels=labels,
        located=located,
        channels=channels,
        effects=(*node.effects, *effects) if effects else node.effects,
        next_label=node.next_label,
        path=node.path if choice is None else (*node.path, choice),
        cost=node.cost + added,
        robots=robots,
        resolved=resolved,
        memory=memory,
        floor=node.floor,
    )


def settle(
    channels: tuple[Channel, ...],
    located: dict[int, Placed],
    touching: list[int],
    resolved: frozenset[ChannelKey],
    task: Task,
) -> tuple[tuple[Channel, ...], float, frozenset[ChannelKey]] | DeadEnd:
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
            return _misplaced(ch, src, dst)
        ident = (ch.kind, ch.source, ch.target, ch.data)
        if ident not in resolved and ident not in new:
            new.add(ident)
            added += task.channel_cost(ch.kind)
            if ch.kind == "global":
                added += task.link_cost(src.robot, dst.robot)
            continue
        # An identical channel is already there (rare): keep it, drop this one.
        j = next(
            j
            for j, c in enumerate(out)
            if j != i
            and j not in dropped
            and (c.kind, c.source, c.target, c.data) == ident
            and c.source in located
            and c.target in located
        )
        kept = out[j]
        if ch.bandwidth is not None and (kept.bandwidth is None or ch.bandwidth > kept.bandwidth):
            out[j] = Channel(
                kept.kind,
                kept.robots,
                kept.source,
                kept.target,
                kept.data,
                ch.bandwidth,
                ch.number,  # the number of (kind, robots, data) with ch's bandwidth
            )
        dropped.append(i)
    if dropped:
        out = [c for i, c in enumerate(out) if i not in dropped]
    if task.media and any(k == "global" for k, *_ in new):
        overflow = _media(out, located, task)
        if overflow is not None:
            return overflow
    return tuple(out), added, resolved | new if new else resolved


def demands(channels: Sequence[Channel], located: dict[int, Placed]) -> list[Demand | None]:
    """What each channel needs of the media, in order: a global channel whose
    two ends are placed on different robots needs its bandwidth; any other
    needs nothing (None)."""
    out: list[Demand | None] = []
    for ch in channels:
        src, dst = located.get(ch.source), located.get(ch.target)
        if ch.kind == "global" and src is not None and dst is not None and src.robot != dst.robot:
            out.append(Demand(src.robot, dst.robot, ch.bandwidth or 0.0))
        else:
            out.append(None)
    return out


def _media(channels: list[Channel], located: dict[int, Placed], task: Task) -> DeadEnd | None:
    """Communication admissibility (4.6) of the global channels whose two ends
    are placed: they are final (a merge only raises a bandwidth), so if they
    overflow the media now, every completion does (step 4 would reject it)."""
    result = assign(demands(channels, located), task.media, clock.check)
    if result.ok:
        return None
    return DeadEnd("configuration", result.problem, None, Condition.COMMUNICATION)


def _misplaced(ch: Channel, src: Placed, dst: Placed) -> DeadEnd:
    return DeadEnd(
        f"{ch.kind} channel {atom_text(ch.data)}",
        f"declared ({ch.kind} {' '.join(ch.robots)}) but it runs from "
        f"{call_text(src.call)} on {src.robot} to "
        f"{call_text(dst.call)} on {dst.robot}",
        condition=Condition.LOCATION,
    )
