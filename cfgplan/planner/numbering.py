"""Small whole numbers for the values search nodes are made of.

A node's canonical form (:func:`cfgplan.planner.canonical.canonical`) and a
configuration's fingerprint (:func:`cfgplan.planner.finish.fingerprint`) are
sets of instances, channels and postconditions. Numbering each distinct value
once per task lets both be written as a short run of integers — equal values
(Python's ``==``: a bandwidth 1 is 1.0), equal numbers; different values,
different numbers — instead of texts made anew for every node. The table
lives as long as the task's grounding memo and grows with the distinct
values its searches meet. It is the task's one numbering: the partitioned
bound numbers its keys (instances, agents, channels as it prices them) from
it too (:attr:`cfgplan.planner.partition.Partition.number`).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any


@dataclass(eq=False, repr=False)
class Numbering:
    """Numbers 0, 1, 2, ... for values, in the order they are first asked for."""

    numbers: dict[Hashable, int] = field(default_factory=dict)
    _written: dict[Callable[[Any], str], dict[Hashable, int]] = field(default_factory=dict)

    def __call__(self, value: Hashable) -> int:
        found = self.numbers.get(value)
        if found is None:
            found = self.numbers[value] = len(self.numbers)
        return found

    def text(self, value: Hashable, write: Callable[[Any], str]) -> int:
        """The number of ``write(value)``: values written alike share it
        (``write`` is called once per value)."""
        memo = self._written.get(write)
        if memo is None:
            memo = self._written[write] = {}
        found = memo.get(value)
        if found is None:
            found = memo[value] = self(write(value))
        return found
