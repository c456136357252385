"""What a search node remembers of the sub-derivations it closed, for
replays (:mod:`cfgplan.planner.replay`, which has the rules): the records of
closed sub-derivations and the expansions still open. A node carries its
:class:`Memory` (:attr:`cfgplan.planner.partial.Partial.memory`); none of
it is ever written once made."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

from cfgplan.planner.ground import Expansion
from cfgplan.planner.task import Ground


def _joined(parts: list[tuple[int, ...]]) -> tuple[int, ...]:
    """The tuples ``parts`` end to end, concatenated two by two: each element
    is copied about log2(len(parts)) times, and a concatenation copies in a
    quarter of the time a list extended then made a tuple does (a dag's walks
    are millions of choices long; a body may have many method items)."""
    while len(parts) > 1:
        pairs = range(0, len(parts) - 1, 2)
        parts = [parts[i] + parts[i + 1] for i in pairs] + parts[len(pairs) * 2 :]
    return parts[0]


@dataclass(eq=False, slots=True)
class Record:
    """A closed sub-derivation: the method instance ``call`` expanded by
    ``expansion``, and the records of its body's method items, in body order
    (a record is shared by every sub-derivation that replayed it)."""

    call: Ground
    choice: int
    """Its expansion's number among the method's (as successors numbers them)."""
    expansion: Expansion
    children: tuple[Record, ...]
    at: dict[int, Record]
    """The children by their body offset."""
    _flat: tuple[int, ...] | None = None
    _size: int = -1
    _effects: tuple[tuple[bool, Ground], ...] | None = None
    _calls: frozenset[Ground] | None = None

    @property
    def flat(self) -> tuple[int, ...]:
        """The choices of the walk, in path order (this expansion's, then each
        child's in body order)."""
        if self._flat is None:
            self._flat = _joined([(self.choice,), *(child.flat for child in self.children)])
        return self._flat

    @property
    def size(self) -> int:
        """The labels the walk takes: every body item of every expansion."""
        if self._size < 0:
            self._size = self.expansion.size + sum(c.size for c in self.children)
        return self._size

    @property
    def effects(self) -> tuple[tuple[bool, Ground], ...]:
        """The postconditions the walk's expansions add, in their order."""
        if self._effects is None:
            effects = list(self.expansion.effects)
            for child in self.children:
                effects.extend(child.effects)
            self._effects = tuple(effects)
        return self._effects

    @property
    def calls(self) -> frozenset[Ground]:
        """The method instances the walk expands (the recursion guard's concern)."""
        if self._calls is None:
            calls = {self.call}
            for child in self.children:
                calls |= child.calls
            self._calls = frozenset(calls)
        return self._calls

    def source(self, data: Ground) -> tuple[Ground, float | None] | None:
        """Where a channel of ``data`` sent from this instance starts once the
        walk re-wired it through each ``:out`` (4.5 step 3d): the functionality
        call, and the bandwidth of the first ``:out`` on the way that has one
        (the one a global channel without takes); None when a ``:out`` is
        missing."""
        record = self
        bandwidth = None
        while True:
            expansion = record.expansion
            port = expansion.outputs.get(data)
            if port is None:
                return None
            if bandwidth is None:
                bandwidth = port[1]
            child = record.at.get(port[0])
            if child is None:
                return expansion.body[port[0]], bandwidth
            record = child

    def targets(self, data: Ground) -> tuple[Ground, ...] | None:
        """Where a channel of ``data`` received by this instance ends once
        re-wired through each ``:in`` (an ``:in`` may feed several): the
        functionality calls in channel order; None when an ``:in`` is missing."""
        expansion = self.expansion
        offsets = expansion.inputs.get(data)
        if not offsets:
            return None
        ends: list[Ground] = []
        for offset in offsets:
            child = self.at.get(offset)
            if child is None:
                ends.append(expansion.body[offset])
                continue
            inner = child.targets(data)
            if inner is None:
                return None
            ends.extend(inner)
        return tuple(ends)


class Opening(NamedTuple):
    """A method instance expanded whose sub-derivation is not closed yet (a
    named tuple: one is made for every expansion remembered)."""

    call: Ground
    choice: int
    expansion: Expansion
    depth: int
    """The stack's length once it is closed (its item's stack, less it)."""
    children: tuple[Record, ...] = ()
    pure: bool = True
    """No functionality binding was chosen in it (those are not replayed:
    the instance reused would take no choice there)."""


class Memory(NamedTuple):
    """What a node remembers for replays: the expansions still open, innermost
    last, and a record for each repeatable instance it closed (the first;
    never written: a close copies it)."""

    opened: tuple[Opening, ...]
    records: Mapping[Ground, Record]
