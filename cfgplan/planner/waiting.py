"""The channels of a node that wait for an end, as the first bound prices
them (:meth:`cfgplan.planner.bound.Bound.estimate`): which end each will
have where that is known already (:func:`sort_channels`), and the parts of
the least costs they make (:func:`waiting_parts`), named by their data
predicates, apart where they can merge with nothing a pending item makes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Set

from cfgplan.planner.partial import Partial
from cfgplan.planner.parts import Part, own_part
from cfgplan.planner.summary import ChannelId, Summary
from cfgplan.planner.task import Ground

Resolved = tuple[str, Ground, Ground, Ground]
"""A channel whose two ends are placed: kind, data, sender, receiver."""

APART = own_part("channels")
"""The part of the channels waiting for an end that merge with nothing pending."""


def sort_channels(
    node: Partial,
    pending: dict[int, tuple[Ground, Summary]],
    methods: dict[int, Ground],
    future: set[ChannelId],
) -> set[Resolved]:
    """The node's channels whose two ends are placed; the others go to
    ``future``, each with the ends it is certain to have: a placed
    functionality, a pending one, or the certain producer of its data behind
    a pending method (None where not known). ``pending``: the pending items
    by label, with their summaries; ``methods``: the method items among them."""
    located = node.located.get
    resolved: set[Resolved] = set()
    for ch in node.channels:
        source, target = located(ch.source), located(ch.target)
        if source is not None and target is not None:
            resolved.add((ch.kind, ch.data, source.call, target.call))
            continue
        if source is not None:
            src: Ground | None = source.call
        else:
            src = _pending_end(pending, methods, ch.source, ch.data)
        dst: Ground | None = None
        if target is not None:
            dst = target.call
        elif ch.target not in methods:
            entry = pending.get(ch.target)  # a pending functionality: what it will be
            dst = entry[0] if entry is not None else None
        future.add((ch.kind, ch.data, src, dst))
    return resolved


def unreached_by(
    reach: Callable[[Ground], frozenset[str]], names: Set[str], methods: Iterable[Ground]
) -> set[str]:
    """The functionality ``names`` none of the method instances ``methods``
    can ``reach`` (:meth:`cfgplan.planner.reach.Reach.names`)."""
    left = set(names)
    for call in methods:
        if not left:
            break  # (most often at once: one item reaches every name waiting)
        left.difference_update(reach(call))
    return left


def waiting_parts(
    channel_cost: Callable[[str], float],
    future: set[ChannelId],
    resolved: set[Resolved],
    alone: frozenset[Ground],
    unreached: Set[str],
) -> list[Part]:
    """The channels waiting for an end (``future``) as parts of
    :func:`~cfgplan.planner.parts.least`, in the channels' and the together
    least costs of :meth:`~cfgplan.planner.bound.Bound.estimate`: named
    by their data predicates (parts whose data predicates differ cannot
    merge, so they add up). A channel from or into a functionality in
    ``alone`` can merge with none a pending item makes (those have both
    ends inside its expansion): they are a part of their own. So is a
    channel into a functionality whose name no pending method item can
    reach (``unreached``): a channel an item makes ends at a body item
    of its expansion, which has a name it reaches (on the
    ``dag`` family the channels into the fusers waiting on the stack
    were joined with every level below, by their data)."""
    names: set[str] = set()  # the data predicates of the channels not apart
    full = [0.0, 0.0]  # fully known channels not in C: not apart, apart
    covered: tuple[set[tuple[str, Ground, Ground]], ...] = (set(), set())
    open_ends: tuple[set[tuple[str, Ground, Ground]], ...] = (set(), set())
    apart = bool(alone or unreached)  # (seldom: most nodes have no channel apart)
    for channel in future:
        kind, data, sender, receiver = channel
        side = int(
            apart
            and (
                sender in alone
                or receiver in alone
                or (receiver is not None and receiver[0] in unreached)
            )
        )
        if not side:
            names.add(data[0])
        if receiver is None:
            continue
        if sender is None:
            open_ends[side].add((kind, data, receiver))
        elif channel not in resolved:
            full[side] += channel_cost(kind)
            covered[side].add((kind, data, receiver))
    # Channels certain to be new: fully known ones not in C, plus one per
    # (kind, data, receiver) of those whose sender is unknown and that
    # nothing known could be.
    costs = list(full)
    if open_ends[0] or open_ends[1]:
        known = {(k, d, r) for k, d, _, r in resolved}
        for side in (0, 1):
            for kind, data, receiver in open_ends[side]:
                end = (kind, data, receiver)
                if end not in covered[side] and end not in known:
                    costs[side] += channel_cost(kind)
    parts: list[Part] = [(frozenset(names), costs[0])]
    if costs[1]:
        parts.append((APART, costs[1]))
    return parts


def _pending_end(
    pending: dict[int, tuple[Ground, Summary]], methods: dict[int, Ground], label: int, data: Ground
) -> Ground | None:
    """The certain producer of ``data`` behind a pending label, if there is one."""
    entry = pending.get(label)
    if entry is None:
        return None
    call, sub = entry
    if label not in methods:
        return call
    return sub.producer(data)
