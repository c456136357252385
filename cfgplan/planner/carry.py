"""Carrying the partitioned bound's cheapest costs from one node to the next.

:meth:`cfgplan.planner.partition.Partition.split` prices every ground
instance below a node's pending items, bottom-up, at the node's prices
(:mod:`cfgplan.planner.prices`). Nodes refined one after another differ in
few prices: the search takes a node's children soon after the node, and one
expansion changes the counts of one item's keys, places a few
functionalities, resolves a few channels. On ecology, fusion and media-tight
89-97% of the instances cost the same at the next node refined as at the
last one. So the last node's costs are kept with what they were computed
from (:class:`Basis`), and a node starts from them, less every instance that
reads a price that may differ and every instance above one (:meth:`Carry.start`):

- a key whose count (``totals``) changed: the functionality it stands for,
  the methods whose own channels share it, whose agents it counts;
- a channel key that came into C or left it (``present``);
- a functionality placed or no longer placed;
- an agent that came into use or became certain, or the reverse;
- any change of the media's load: every method with an expansion that needs
  the media.

What is carried is the very float a fresh computation gives (the same sums,
in the same order, of the same values), so the bound, and with it the search,
is unchanged: ``tests/planner/test_carry.py`` compares both at every node.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Set
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cfgplan.planner.prices import Counts
from cfgplan.planner.room import Load
from cfgplan.planner.task import Ground

if TYPE_CHECKING:
    from cfgplan.planner.partition import Instance


@dataclass(frozen=True, slots=True)
class Basis:
    """The prices a memo of cheapest costs was computed at, and the memo."""

    totals: Counts
    present: Set[int]
    placed: Set[Ground]
    agents: frozenset[str]  # in use or certain: they cost nothing more
    load: Load
    memo: dict[int, float]


@dataclass
class Carry:
    """The instances' dependencies, and the last node's costs."""

    number: Callable[[Hashable], int]
    _readers: dict[int, list[int]] = field(default_factory=dict)
    """Key number -> the instances whose own cost reads its price."""
    _parents: dict[int, list[int]] = field(default_factory=dict)
    """Instance -> the methods with it in an expansion."""
    _needy: set[int] = field(default_factory=set)
    """Methods with an expansion the media may not carry."""
    _last: Basis | None = None
    _next: Basis | None = None

    def add(self, instance: Instance) -> None:
        """Index a new instance's dependencies."""
        me = instance.key
        if instance.functionality:
            self._read(me, (me,))
            return
        for option in instance.options:
            for child in option.child_keys:
                self._parents.setdefault(child, []).append(me)
            for own in option.channels:
                self._read(me, (*own.shares, own.free))
            self._read(me, option.agent_keys)
            if option.needs:
                self._needy.add(me)

    def _read(self, reader: int, keys: Iterable[int]) -> None:
        for key in keys:
            readers = self._readers.setdefault(key, [])
            if not readers or readers[-1] != reader:
                readers.append(reader)

    def start(
        self,
        totals: Counts,
        present: Set[int],
        placed: Set[Ground],
        agents: frozenset[str],
        load: Load,
    ) -> dict[int, float]:
        """The costs of the last node still right at these prices (a new
        dict); :meth:`keep` then keeps the memo filled at them."""
        last = self._last
        self._next = Basis(totals, present, placed, agents, load, {})
        if last is None:
            return {}
        changed = {key for key, _ in totals.items() ^ last.totals.items()}
        changed.update(present ^ last.present)
        number = self.number
        changed.update(number(("f", call)) for call in placed ^ last.placed)
        changed.update(number(("@", agent)) for agent in agents ^ last.agents)
        dirty: set[int] = set(self._needy) if load != last.load else set()
        readers = self._readers
        for key in changed:
            dirty.update(readers.get(key, ()))
        parents = self._parents
        todo = list(dirty)
        while todo:
            for parent in parents.get(todo.pop(), ()):
                if parent not in dirty:
                    dirty.add(parent)
                    todo.append(parent)
        memo = dict(last.memo)
        for key in dirty:
            memo.pop(key, None)
        return memo

    def keep(self, memo: dict[int, float]) -> None:
        """The memo :meth:`start` began, now filled: the next node starts from it."""
        if self._next is not None:
            basis = self._next
            self._last = Basis(
                basis.totals, basis.present, basis.placed, basis.agents, basis.load, memo
            )
            self._next = None
