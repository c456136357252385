"""What the media still have room for: a node-level test of communication
admissibility (4.6) that the partitioned bound applies to every expansion
it prices (:mod:`cfgplan.planner.partition`).

A global channel is declared between two robots, ``(global S R)``, when
its method is expanded, and it keeps them whatever it is re-wired to later
(a channel placed elsewhere is a dead end, 4.5 step 4). So every global
channel of a node between two different robots will, in every completion,
load the media from S to R by at least its bandwidth (0 while unknown: a
channel sent from a method gets its bandwidth from that method's ``:out``
when it is expanded). Channels are merged only when they are identical
(same kind, ends and data), and a merge keeps the larger bandwidth; so the
channels of one *group* — robot pair, kind and data — load the pair by at
least the largest bandwidth among them, and different groups add up.

An expansion whose own global channels would, on top of that load, need
more from a pair than all its media together carry (or more than its
largest medium for one channel, or a medium where there is none) has no
admissible completion below this node: the bound prices it as impossible.
That is what makes a member that takes a raw image stream (40) from a
camera host over a medium of 40 unable to take its pose (5) from the same
host too, before either is placed.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

from cfgplan.planner.ground import ChannelSpec
from cfgplan.planner.task import Task
from cfgplan.planner.wiring import Channel


class Need(NamedTuple):
    """An expansion's own global channels of one group: the group's number,
    its robot pair's number and the largest bandwidth among them."""

    group: int
    pair: int
    bandwidth: float


Load = dict[int, float]
"""The least load of a node by group number, and by ``-1 - pair`` for each
pair's sum over its groups."""


@dataclass(eq=False, repr=False)
class Room:
    """The media of one task, by robot pair: what they carry together and
    the largest of them (a channel is never split over two media)."""

    task: Task
    number: Callable[[Hashable], int]
    media: bool = True
    """False: ask nothing of the media (:attr:`SearchOptions.media
    <cfgplan.planner.options.SearchOptions.media>`)."""

    def __post_init__(self) -> None:
        self._groups: dict[tuple[str, tuple[str, ...], object], tuple[int, int] | None] = {}
        self.total: dict[int, float] = {}
        self.largest: dict[int, float] = {}
        for medium in self.task.media:
            pair = self.number(("<>", medium.sender, medium.receiver))
            self.total[pair] = self.total.get(pair, 0.0) + medium.capacity
            self.largest[pair] = max(self.largest.get(pair, 0.0), medium.capacity)

    @property
    def active(self) -> bool:
        """Without media every channel fits (4.6 applies only when declared)."""
        return self.media and bool(self.task.media)

    def pair(self, kind: str, robots: Sequence[str]) -> int | None:
        """The number of the robot pair a channel of ``kind`` declared
        between ``robots`` loads; None when it needs no medium."""
        if kind != "global" or len(robots) != 2 or robots[0] == robots[1]:
            return None
        return self.number(("<>", robots[0], robots[1]))

    def _group(self, kind: str, robots: Sequence[str], data: object) -> tuple[int, int] | None:
        """The numbers of a channel's group and robot pair (None: it needs no
        medium), made once per (kind, robots, data)."""
        ident = (kind, tuple(robots), data)
        try:
            return self._groups[ident]
        except KeyError:
            pass
        pair = self.pair(kind, robots)
        found = None
        if pair is not None:
            found = self.number(("<>", robots[0], robots[1], kind, data)), pair
        self._groups[ident] = found
        return found

    def needs(self, specs: Sequence[ChannelSpec]) -> tuple[Need, ...]:
        """The needs of an expansion's own channels, one per group."""
        if not self.active:
            return ()
        largest: dict[tuple[int, int], float] = {}
        for kind, robots, _, _, data, bandwidth in specs:
            found = self._group(kind, robots, data)
            if found is not None:
                largest[found] = max(largest.get(found, 0.0), bandwidth or 0.0)
        return tuple(Need(group, pair, b) for (group, pair), b in largest.items())

    def load(self, channels: Iterable[Channel]) -> Load:
        """The least load every completion of a node with ``channels`` (resolved
        or waiting for an end) puts on the media."""
        load: Load = {}
        if not self.active:
            return load
        for ch in channels:
            found = self._group(ch.kind, ch.robots, ch.data)
            if found is None:
                continue
            group, pair = found
            b = ch.bandwidth or 0.0
            before = load.get(group, 0.0)
            if b > before or group not in load:
                load[group] = max(b, before)
                load[-1 - pair] = load.get(-1 - pair, 0.0) + max(b - before, 0.0)
        return load

    def fits(self, needs: tuple[Need, ...], load: Load) -> bool:
        """Whether the media can carry ``needs`` on top of ``load``."""
        added: dict[int, float] = {}
        for need in needs:
            largest = self.largest.get(need.pair)
            if largest is None or need.bandwidth > largest:
                return False
            more = need.bandwidth - load.get(need.group, 0.0)
            if more > 0:
                added[need.pair] = added.get(need.pair, 0.0) + more
        for pair, more in added.items():
            if load.get(-1 - pair, 0.0) + more > self.total[pair] + 1e-9:
                return False
        return True
