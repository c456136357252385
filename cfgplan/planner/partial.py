"""A partial configuration: the search node of the planner (thesis 4.5).

It holds the method stack, the functionalities added so far (C), the channels
(Ch), the collected postconditions (P) and the label counter. The two steps of
4.5 that grow it are here: :func:`expand_method` (step 3) and
:func:`place_functionality` / :func:`reuse_functionality` (step 2a); how they
re-wire and settle its channels is :mod:`cfgplan.planner.wiring`. Every step
returns a new node or a :class:`DeadEnd` with its reason; nodes are never
mutated once built, so the search can keep many of them.

Labels: the goal is label 1 and every instance a method body creates takes
the next number, in body order, when the method is expanded. A reused
functionality keeps the label of its first instance.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from cfgplan.ir.model import Span
from cfgplan.notation import atom_text
from cfgplan.planner.ground import Expansion, FunctionalityInstance
from cfgplan.planner.memory import Memory
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import FunctionalitySchema, Ground, Task
from cfgplan.planner.wiring import Channel, ChannelKey, Port, Unwired, rewire, settle


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
class Placed:
    """A functionality instance in the configuration, located at ``robot``
    (its first argument), with its inputs and outputs instantiated."""

    label: int
    call: Ground
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
    labels: dict[Ground, int]  # functionality instance -> its label
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
        effects=node.effects + expansion.effects if expansion.effects else node.effects,
        next_label=first + expansion.size,
        # Concatenated, not unpacked (RUF005): it copies in a quarter of the
        # time, and a dag's replayed paths are millions of choices long.
        path=node.path + (choice,),  # noqa: RUF005
        cost=node.cost,
        robots=node.robots,
        resolved=node.resolved,
        memory=memory,
        floor=node.floor,
    )


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
    added += task.costs.functionality(schema, item.call)
    robots = node.robots
    if new.robot not in robots:
        added += task.costs.agent(new.robot)
        robots = robots | {new.robot}
    labels = dict(node.labels)
    labels[item.call] = item.label
    return Partial(
        stack=node.stack[1:],
        placed=node.placed + (new,),  # noqa: RUF005 (faster: see expand_method)
        labels=labels,
        located=located,
        channels=channels,
        effects=node.effects + effects if effects else node.effects,
        next_label=node.next_label,
        path=node.path if choice is None else node.path + (choice,),  # noqa: RUF005
        cost=node.cost + added,
        robots=robots,
        resolved=resolved,
        memory=memory,
        floor=node.floor,
    )
