"""Step 4 of thesis 4.5: when the stack is empty, verify the configuration is
admissible (3.5) and return it.

Causal admissibility and channel locations were checked as the configuration
grew; here remain information (every input fed), cycles (5.1) and, when the
state declares media, communication (4.6). :func:`finish` returns the
:class:`Configuration`, or the :class:`DeadEnd` saying which condition it broke.
"""

from __future__ import annotations

from collections.abc import Container
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

from cfgplan.configuration.media import assign
from cfgplan.configuration.model import Assignment, Channel, Configuration, FunctionalityInstance
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.ground import Effects, Numbering
from cfgplan.planner.partial import Channel as PartialChannel
from cfgplan.planner.partial import Partial, Placed, channel_numbers, demands, digest, placed_names
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import Ground, Task


@dataclass(eq=False, repr=False)
class Models:
    """Result models already built, keyed by everything they hold: the models
    are immutable, so the configurations of one search share them."""

    functionalities: dict[tuple[int, Ground], FunctionalityInstance] = field(default_factory=dict)
    channels: dict[tuple[object, ...], Channel] = field(default_factory=dict)


def _label(n: int) -> str:
    return f"F{n}"


def _information(node: Partial, given: Container[int] = ()) -> DeadEnd | None:
    """Every input of every functionality (but those labelled in ``given``)
    has a channel carrying its descriptor, from a functionality that produces
    it; a sender runs at least as often as its receiver when both declare
    ``:freq``."""
    located = node.located
    fed: set[tuple[int, tuple[str, ...]]] = set()
    for ch in node.channels:
        src = located[ch.source]
        if ch.data not in src.outputs:
            return DeadEnd(
                call_text(src.call),
                f"does not produce {atom_text(ch.data)}",
                None,
                Condition.INFORMATION,
            )
        dst = located[ch.target]
        if ch.data not in dst.inputs:
            return DeadEnd(
                call_text(dst.call),
                f"does not consume {atom_text(ch.data)}",
                None,
                Condition.INFORMATION,
            )
        slow = src.schema.freq, dst.schema.freq
        if slow[0] is not None and slow[1] is not None and slow[0] < slow[1]:
            return DeadEnd(
                call_text(src.call),
                f"runs at {slow[0]:g} Hz but feeds {call_text(dst.call)} at {slow[1]:g} Hz",
                None,
                Condition.INFORMATION,
            )
        fed.add((ch.target, ch.data))
    for p in node.placed:
        if p.label in given:
            continue
        for need in p.inputs:
            if (p.label, need) not in fed:
                return DeadEnd(
                    call_text(p.call),
                    f"input {atom_text(need)} is fed by no channel",
                    None,
                    Condition.INFORMATION,
                )
    return None


def _cycle(node: Partial) -> DeadEnd | None:
    """A cycle among the functionalities (the sort of 5.1 would fail), named by
    the functionalities on it (a channel from a functionality to itself is one)."""
    succ: dict[int, set[int]] = {p.label: set() for p in node.placed}
    indegree = dict.fromkeys(succ, 0)
    for ch in node.channels:
        if ch.target not in succ[ch.source]:
            succ[ch.source].add(ch.target)
            indegree[ch.target] += 1
    ready = [n for n, d in indegree.items() if d == 0]
    seen = 0
    while ready:
        n = ready.pop()
        seen += 1
        for m in succ[n]:
            indegree[m] -= 1
            if indegree[m] == 0:
                ready.append(m)
    if seen == len(succ):
        return None
    stuck = {n for n, d in indegree.items() if d > 0}
    on_cycle = _on_cycle(succ, stuck)
    names = ", ".join(f"{_label(n)} {call_text(node.located[n].call)}" for n in on_cycle)
    return DeadEnd(
        "configuration", f"its channels form a cycle through {names}", None, Condition.CYCLE
    )


def _on_cycle(succ: dict[int, set[int]], stuck: set[int]) -> list[int]:
    """One cycle among ``stuck`` (the nodes the sort could not take), in the
    order of its channels, starting at its lowest label. Every stuck node has
    a stuck predecessor, so walking backwards from any of them must repeat."""
    pred: dict[int, int] = {}
    for n in sorted(stuck):
        for m in sorted(succ[n]):
            if m in stuck:
                pred.setdefault(m, n)
    walk: list[int] = []
    current = min(stuck)
    while current not in walk:
        walk.append(current)
        current = pred[current]
    cycle = walk[walk.index(current) :]
    cycle.reverse()  # walked backwards: now in channel order
    start = cycle.index(min(cycle))
    return cycle[start:] + cycle[:start]


def _postcondition(effect: tuple[bool, Ground]) -> str:
    positive, atom = effect
    return atom_text(atom) if positive else f"(not {atom_text(atom)})"


def postconditions(node: Finished) -> tuple[str, ...]:
    """P as the thesis prints it: atoms and ``(not ATOM)``, each once, in order."""
    return tuple(dict.fromkeys(map(_postcondition, node.effects)))


def fingerprint(node: Partial, number: Numbering) -> bytes:
    """The configuration of a complete node without its labels —
    :meth:`Configuration.identity`: its functionality instances, its channels
    with their ends named by instance, and P — as a 128-bit :func:`digest`,
    without building the configuration. Two configurations
    are the same when their fingerprints are; it takes 16 bytes, so every
    configuration listed can be remembered. A channel's robots follow from
    its ends, so they add nothing."""
    names = placed_names(node)
    ends = sorted(set(names.values()))
    channels = sorted(set(channel_numbers(node, names, number)))
    post = sorted({number.text(effect, _postcondition) for effect in node.effects})
    return digest([len(ends), *ends, len(channels), *channels, *post])


class Finished(Protocol):
    """What a configuration is built from: a complete :class:`Partial`, or
    the three parts of one kept to be built later (:class:`Pieces`)."""

    @property
    def placed(self) -> tuple[Placed, ...]: ...
    @property
    def channels(self) -> tuple[PartialChannel, ...]: ...
    @property
    def effects(self) -> Effects: ...


class Pieces(NamedTuple):
    """A complete node's parts a configuration is built from: smaller than
    the node (no stack, no indexes), to hold many until they are listed."""

    placed: tuple[Placed, ...]
    channels: tuple[PartialChannel, ...]
    effects: Effects


def build(
    node: Finished,
    total: float,
    task: Task,
    models: Models,
    media: tuple[Assignment, ...] = (),
    derivation: int = 0,
) -> Configuration:
    """The configuration of a finished node, in the thesis's list order, with
    its media assignment and its derivation number (in listing order).

    The models are validated as they are made: pydantic's validation (in
    Rust) takes half the time of ``model_construct`` (a Python loop) on these,
    and a model given as a field is taken as it is, not validated again (it is
    the hot path of listing many configurations). ``models`` shares the
    immutable parts between configurations.
    """
    robot = {p.label: p.robot for p in node.placed}
    functionalities: list[FunctionalityInstance] = []
    for p in reversed(node.placed):
        fkey = (p.label, p.call)
        made = models.functionalities.get(fkey)
        if made is None:
            made = models.functionalities[fkey] = FunctionalityInstance(
                label=_label(p.label), name=p.call[0], args=p.call[1:]
            )
        functionalities.append(made)
    channels: list[Channel] = []
    for ch in node.channels:
        src, dst = robot[ch.source], robot[ch.target]
        ckey = (ch.kind, ch.source, ch.target, src, dst, ch.data, ch.bandwidth)
        cmade = models.channels.get(ckey)
        if cmade is None:
            cmade = models.channels[ckey] = Channel(
                kind="global" if ch.kind == "global" else "local",
                source=_label(ch.source),
                target=_label(ch.target),
                source_robot=src,
                target_robot=dst,
                data=ch.data,
                bandwidth=ch.bandwidth,
            )
        channels.append(cmade)
    return Configuration(
        functionalities=tuple(functionalities),
        channels=tuple(channels),
        postconditions=postconditions(node),
        cost=total,
        weights=task.weights,
        media=media,
        derivation=derivation,
        proven=True,
        devices=_devices(node, task),
        reliability=_reliability(node, robot, task),
        effects=tuple(dict.fromkeys(node.effects)),
    )


def _devices(node: Finished, task: Task) -> tuple[str, ...]:
    """The agents of the configuration the state declares devices, in the
    order of its functionality list."""
    if not task.devices:
        return ()
    agents = dict.fromkeys(p.robot for p in reversed(node.placed))
    return tuple(a for a in agents if a in task.devices)


def _reliability(node: Finished, robot: dict[int, str], task: Task) -> float:
    """The product of the reliabilities of its functionalities and of the
    media its global channels between two robots use (7.2)."""
    if not task.uncertain:
        return 1.0
    reliability = 1.0
    for p in node.placed:
        reliability *= task.functionality_reliability(p.schema, p.call)
    for ch in node.channels:
        src, dst = robot[ch.source], robot[ch.target]
        if ch.kind == "global" and src != dst:
            reliability *= task.links.get((src, dst), 1.0)
    return reliability


def admissible(
    node: Partial, task: Task, given: Container[int] = ()
) -> tuple[Assignment, ...] | DeadEnd:
    """Step 4's checks left for a finished node — information, cycles and,
    when the state declares media, communication: the media assignment
    (empty without media), or the condition it breaks. The functionalities
    labelled in ``given`` may have inputs fed from elsewhere (an independent
    part's search, :mod:`cfgplan.planner.combine`)."""
    for dead in (_information(node, given), _cycle(node)):
        if dead is not None:
            return dead
    if not task.media:
        return ()
    result = assign(demands(node.channels, node.located), task.media, clock.check)
    if result.assignment is None:
        return DeadEnd("configuration", result.problem, None, Condition.COMMUNICATION)
    return tuple(Assignment(channel=c, medium=m) for c, m in result.assignment.items())


def finish(
    node: Partial, task: Task, total: float, models: Models | None = None, derivation: int = 0
) -> Configuration | DeadEnd:
    """The admissible configuration of a finished node, or why it is not."""
    media = admissible(node, task)
    if isinstance(media, DeadEnd):
        return media
    return build(node, total, task, Models() if models is None else models, media, derivation)
