"""Step 4 of thesis 4.5: when the stack is empty, verify the configuration is
admissible (3.5) and return it.

Causal admissibility and channel locations were checked as the configuration
grew; here remain information (every input fed), cycles (5.1) and, when the
state declares media, communication (4.6).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cfgplan.configuration.media import Demand, assign
from cfgplan.configuration.model import Assignment, Channel, Configuration, FunctionalityInstance
from cfgplan.planner.partial import Dead, Partial, describe_call
from cfgplan.planner.task import Task, show

if TYPE_CHECKING:
    from cfgplan.planner.search import Report


def _label(n: int) -> str:
    return f"F{n}"


def _information(node: Partial) -> Dead | None:
    """Every input of every functionality has a channel carrying its descriptor,
    from a functionality that produces it."""
    located = node.located
    fed: set[tuple[int, tuple[str, ...]]] = set()
    for ch in node.channels:
        src = located[ch.source]
        if ch.data not in src.outputs:
            return Dead(
                describe_call(src.call),
                f"does not produce {show(ch.data)}",
                condition="information",
            )
        dst = located[ch.target]
        if ch.data not in dst.inputs:
            return Dead(
                describe_call(dst.call),
                f"does not consume {show(ch.data)}",
                condition="information",
            )
        slow = src.schema.freq, dst.schema.freq
        if slow[0] is not None and slow[1] is not None and slow[0] < slow[1]:
            return Dead(
                describe_call(src.call),
                f"runs at {slow[0]:g} Hz but feeds {describe_call(dst.call)} at {slow[1]:g} Hz",
                condition="information",
            )
        fed.add((ch.target, ch.data))
    for p in node.placed:
        for need in p.inputs:
            if (p.label, need) not in fed:
                return Dead(
                    describe_call(p.call),
                    f"input {show(need)} is fed by no channel",
                    condition="information",
                )
    return None


def _cycle(node: Partial) -> Dead | None:
    """A cycle among the functionalities (the sort of 5.1 would fail)."""
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
    on_cycle = sorted(_label(n) for n, d in indegree.items() if d > 0)
    return Dead(
        "configuration",
        "its channels form a cycle through " + ", ".join(on_cycle),
        condition="cycle",
    )


def _postconditions(node: Partial) -> tuple[str, ...]:
    post = (show(a) if positive else f"(not {show(a)})" for positive, a in node.effects)
    return tuple(dict.fromkeys(post))


def identity(node: Partial) -> object:
    """:meth:`Configuration.identity` of the node's configuration, without building it."""
    key = {p.label: p.call for p in node.placed}
    channels = frozenset(
        (ch.kind, key[ch.source], key[ch.target], ch.data, ch.bandwidth) for ch in node.channels
    )
    return frozenset(key.values()), channels, frozenset(_postconditions(node))


def build(node: Partial, total: float, task: Task) -> Configuration:
    """The configuration of a finished node, in the thesis's list order.

    The planner's own data is already valid, so the models are constructed
    without validation (it is the hot path of listing many configurations).
    """
    located = node.located
    cache = task.models  # the models are immutable: configurations share them
    functionalities = []
    for p in reversed(node.placed):
        fkey = (p.label, p.call)
        made = cache.get(fkey)
        if made is None:
            made = cache[fkey] = FunctionalityInstance.model_construct(
                label=_label(p.label), name=p.call[0], args=p.call[1:]
            )
        functionalities.append(made)
    channels = []
    for ch in node.channels:
        src, dst = located[ch.source].robot, located[ch.target].robot
        ckey = (ch.kind, ch.source, ch.target, src, dst, ch.data, ch.bandwidth)
        made = cache.get(ckey)
        if made is None:
            made = cache[ckey] = Channel.model_construct(
                kind="global" if ch.kind == "global" else "local",
                source=_label(ch.source),
                target=_label(ch.target),
                source_robot=src,
                target_robot=dst,
                data=ch.data,
                bandwidth=ch.bandwidth,
            )
        channels.append(made)
    return Configuration.model_construct(
        functionalities=tuple(functionalities),
        channels=tuple(channels),
        postconditions=_postconditions(node),
        cost=total,
        weights=task.weights,
        media=(),
        derivation=0,
        proven=True,
    )


def demands(config: Configuration) -> list[Demand | None]:
    """What each channel needs of the media: global channels between two robots."""
    return [
        Demand(c.source_robot, c.target_robot, c.bandwidth or 0.0)
        if c.kind == "global" and c.source_robot != c.target_robot
        else None
        for c in config.channels
    ]


def finish(node: Partial, task: Task, total: float, report: Report) -> Configuration | None:
    """The admissible configuration of a finished node, or None (reason reported)."""
    for dead in (_information(node), _cycle(node)):
        if dead is not None:
            report.rejected.append((dead.condition, f"{dead.where}: {dead.reason}"))
            return None
    config = build(node, total, task)
    if task.media:
        result = assign(demands(config), task.media)
        if not result.ok:
            report.rejected.append(("communication", result.problem))
            return None
        assert result.assignment is not None
        config = config.model_copy(
            update={
                "media": tuple(
                    Assignment(channel=c, medium=m) for c, m in result.assignment.items()
                )
            }
        )
    return config
