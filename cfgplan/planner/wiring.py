"""The channels of a partial configuration (thesis 4.5): how a method's
expansion re-wires those at the expanded instance (step 3d, :func:`rewire`),
and how they settle once both their ends are placed (step 2a,
:func:`settle`): their location checked, an identical one merged, the
media's room for the global ones checked early (4.6), as step 4 would.
The node they belong to, and the steps that call these, are
:mod:`cfgplan.planner.partial`'s.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol

from cfgplan.configuration.media import Demand, assign
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import Ground, Task


class Located(Protocol):
    """What settling a channel reads of a functionality placed at one end
    (:class:`cfgplan.planner.partial.Placed`): its call and its robot."""

    @property
    def call(self) -> Ground: ...
    @property
    def robot(self) -> str: ...


ChannelKey = tuple[str, int, int, Ground]
"""A resolved channel's identity: kind, sender label, receiver label, data."""


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


Port = tuple[int, float | None]
"""Where a channel's sending end goes once re-wired: a label, and the bandwidth
of the ``:out`` entry it went through (None: it has none)."""


class Unwired(NamedTuple):
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
    expansion's ports (:func:`cfgplan.planner.partial.expand_method`) or a
    replayed walk's, port after port (:func:`cfgplan.planner.replay.replay`)."""
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


def settle(
    channels: tuple[Channel, ...],
    located: Mapping[int, Located],
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
    new_global = False  # a global channel newly resolved: the media may overflow
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
            added += task.costs.channel(ch.kind)
            if ch.kind == "global":
                added += task.costs.link(src.robot, dst.robot)
                new_global = True
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
    if new_global and task.media:
        overflow = _media(out, located, task)
        if overflow is not None:
            return overflow
    return tuple(out), added, resolved | new if new else resolved


def demands(channels: Sequence[Channel], located: Mapping[int, Located]) -> list[Demand | None]:
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


def _media(channels: list[Channel], located: Mapping[int, Located], task: Task) -> DeadEnd | None:
    """Communication admissibility (4.6) of the global channels whose two ends
    are placed: they are final (a merge only raises a bandwidth), so if they
    overflow the media now, every completion does (step 4 would reject it)."""
    result = assign(demands(channels, located), task.media, clock.check)
    if result.ok:
        return None
    return DeadEnd("configuration", result.problem, None, Condition.COMMUNICATION)


def _misplaced(ch: Channel, src: Located, dst: Located) -> DeadEnd:
    return DeadEnd(
        f"{ch.kind} channel {atom_text(ch.data)}",
        f"declared ({ch.kind} {' '.join(ch.robots)}) but it runs from "
        f"{call_text(src.call)} on {src.robot} to "
        f"{call_text(dst.call)} on {dst.robot}",
        condition=Condition.LOCATION,
    )
