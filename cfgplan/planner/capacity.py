"""How often a shared cost can occur where the media limit the expansions
that bring it (4.6): a cap on the divisors of the partitioned bound
(:mod:`cfgplan.planner.partition`).

The partitioned bound divides a shared cost ``w`` (a functionality instance,
a robot or device) among the S times it can occur in the pending items'
derivations. When every expansion that brings it (its *carriers*) also sends
a global channel of its own between one pair of robots, it can occur only as
often as that pair's media carry such channels: N robots that may each crop
their view from one ceiling camera, each view 30 over the camera's link of
40, use that camera once among them, not N times. Dividing ``w`` by the
smaller number is as admissible as dividing by S: in every admissible
completion the cost is charged at most as often as it occurs. It is what
tells the bound that each robot pays for a camera of its own; without it the
search tries the partial assignments of robots to cameras (factorial in N)
before it accepts its first configuration.

A key (functionality instance or agent) is capped on a pair P when, over the
ground instances made so far:

- every carrier expansion brings it once and needs P (bandwidth above 0,
  :class:`cfgplan.planner.room.Need`);
- the groups (pair, kind, data) it needs on P are not needed on P by a
  carrier of another ground instance, so no two carriers' channels merge;

and, at a node, no carrier instance occurs twice in one derivation of the
pending items together. The carriers a completion uses then each add a group
of their own to P: those whose group the node already loads, plus at most
``room / b`` more (``room``: what P's media carry beyond the node's load,
``b``: the least a carrier adds). The pending items that are the
functionality itself (or run on the agent) occur besides.

What the argument rests on: the load of a pair counts each group once, at
its largest bandwidth, so what matters is that the carriers' groups are
distinct (a carrier's channel merging with one that is not a carrier's
does no harm); a global channel keeps its two robots, a bandwidth written
in a method is never lowered (a merge keeps the larger, one left unset is
filled from ``:out``) (:mod:`cfgplan.planner.room`); and every instance
below the pending items exists when :meth:`Capacity.lower` runs (the
partitioned bound counts them first), so no carrier is missed.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

from cfgplan.planner.prices import Counts, add, most
from cfgplan.planner.room import Load, Room
from cfgplan.planner.task import Ground, Task

if TYPE_CHECKING:
    from cfgplan.planner.graph import Instance, Option

UNLIMITED = 1 << 40
"""More carriers than any count of occurrences: what is not capped."""

STACKS = 64
"""Stacks whose capped keys are kept, then forgotten all at once (as the
partitioned bound keeps their counts)."""


class Limit(NamedTuple):
    """The carriers of one key on one pair: the least bandwidth one adds, and
    the groups each carrier instance may add (by instance number)."""

    pair: int
    bandwidth: float
    groups: tuple[tuple[int, frozenset[int]], ...]


class Capped(NamedTuple):
    """A key capped at one stack of pending items: its limits, and how many
    pending items are the functionality (or run on the agent) themselves."""

    key: int
    limits: tuple[Limit, ...]
    direct: int


@dataclass(eq=False, repr=False)
class Capacity:
    """The caps of one task, made from the AND/OR graph of its ground
    instances (``instances``, ``order``: :class:`cfgplan.planner.graph.Graph`)."""

    task: Task
    room: Room
    number: Callable[[object], int]
    instances: Mapping[Ground, Instance]
    order: Callable[[Ground], tuple[Instance, ...]]
    _made: int = -1  # how many instances the limits were made from
    _limits: dict[int, tuple[Limit, ...]] = field(default_factory=dict)
    _carriers: frozenset[int] = frozenset()
    _occurs: dict[int, Counts] = field(default_factory=dict)
    _stacks: dict[tuple[Ground, ...], tuple[Capped, ...]] = field(default_factory=dict)

    def lower(self, totals: Counts, calls: tuple[Ground, ...], load: Load) -> dict[int, int]:
        """What the occurrence counts ``totals`` of the pending items
        ``calls`` are lowered to by what the media let occur at a node that
        loads them with ``load``: the keys lowered, with their new totals
        (``totals`` itself is not changed)."""
        lowered: dict[int, int] = {}
        if not self.room.active:
            return lowered
        if len(self.instances) != self._made:
            self._make()
        for capped in self._capped(calls):
            now = totals.get(capped.key)
            if now is None or now <= 1:
                continue
            allowed = min(self._most(limit, load) for limit in capped.limits) + capped.direct
            if allowed < now:
                lowered[capped.key] = max(allowed, 1)
        return lowered

    def _most(self, limit: Limit, load: Load) -> int:
        """How many carriers of ``limit`` a completion of a node with ``load`` uses at most."""
        loaded = sum(1 for _, groups in limit.groups if any(g in load for g in groups))
        room = self.room.total.get(limit.pair, 0.0) - load.get(-1 - limit.pair, 0.0)
        fit = room / limit.bandwidth
        if not fit < UNLIMITED:  # a bandwidth of 1e-300, a capacity of 1e999: no cap
            return UNLIMITED
        return loaded + max(int(fit + 1e-9), 0)

    # -- what is capped at a stack of pending items -----------------------------
    def _capped(self, calls: tuple[Ground, ...]) -> tuple[Capped, ...]:
        found = self._stacks.get(calls)
        if found is None:
            if len(self._stacks) >= STACKS:
                self._stacks.clear()
            found = self._stacks[calls] = self._at(calls)
        return found

    def _at(self, calls: tuple[Ground, ...]) -> tuple[Capped, ...]:
        occurs: Counts = {}
        direct: Counts = {}
        for call in calls:
            if self.task.is_method(call):
                own = self.instances[call].key
                if own in self._carriers:
                    occurs[own] = occurs.get(own, 0) + 1
                for key, n in self._occurrences(call).items():
                    occurs[key] = occurs.get(key, 0) + n
            else:
                for key in (self.number(("f", call)), self.number(("@", call[1]))):
                    direct[key] = direct.get(key, 0) + 1
        capped = []
        for key, limits in self._limits.items():
            kept = tuple(
                limit
                for limit in limits
                if all(occurs.get(instance, 0) <= 1 for instance, _ in limit.groups)
            )
            if kept:
                capped.append(Capped(key, kept, direct.get(key, 0)))
        return tuple(capped)

    def _occurrences(self, call: Ground) -> Counts:
        """Most occurrences of each carrier instance in one derivation of ``call``."""
        for instance in self.order(call):
            if instance.key not in self._occurs:
                self._occurs[instance.key] = most(map(self._option_occurrences, instance.options))
        return self._occurs[self.instances[call].key]

    def _option_occurrences(self, option: Option) -> Counts:
        """The carrier occurrences in a derivation through ``option``."""
        total: Counts = {}
        for child, key in zip(option.children, option.child_keys, strict=True):
            if key in self._carriers:
                total[key] = total.get(key, 0) + 1
            add(total, self._occurs.get(self.instances[child].key, {}))
        return total

    # -- the limits, from the ground instances made so far ------------------------
    def _make(self) -> None:
        self._made = len(self.instances)
        self._occurs.clear()
        self._stacks.clear()
        functionalities = {i.key for i in self.instances.values() if i.functionality}
        carriers: dict[int, list[tuple[int, Option]]] = {}
        for instance in self.instances.values():
            for option in instance.options:
                brought = [k for k in option.child_keys if k in functionalities]
                for key in (*brought, *option.agent_keys):
                    carriers.setdefault(key, []).append((instance.key, option))
                for key in set(brought):
                    if brought.count(key) > 1:
                        carriers[key].append((-1, option))  # brought twice: never capped
        self._limits = {}
        for key, found in carriers.items():
            limits = _limits(found)
            if limits:
                self._limits[key] = limits
        self._carriers = frozenset(
            instance
            for limits in self._limits.values()
            for limit in limits
            for instance, _ in limit.groups
        )


def _limits(carriers: list[tuple[int, Option]]) -> tuple[Limit, ...]:
    """The limits of a key brought by ``carriers`` (instance number, option)."""
    if any(instance < 0 for instance, _ in carriers) or len({i for i, _ in carriers}) < 2:
        return ()
    pairs = set.intersection(
        *({need.pair for need in option.needs if need.bandwidth > 0} for _, option in carriers)
    )
    limits = []
    for pair in sorted(pairs):
        least = float("inf")
        groups: dict[int, set[int]] = {}
        for instance, option in carriers:
            on_pair = [need for need in option.needs if need.pair == pair]
            least = min(least, max(need.bandwidth for need in on_pair))
            groups.setdefault(instance, set()).update(need.group for need in on_pair)
        apart = sum(map(len, groups.values())) == len(set().union(*groups.values()))
        if apart:  # no group is needed by two carrier instances
            limits.append(
                Limit(pair, least, tuple((i, frozenset(g)) for i, g in sorted(groups.items())))
            )
    return tuple(limits)
