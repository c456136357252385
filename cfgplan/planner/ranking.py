"""The order in which configurations are listed, defined once (thesis 4.5, 6.3.2).

The thesis's planner returns configurations cheapest first; at equal cost,
in the order its depth-first expansion derives them (method versions in
domain order, precondition bindings in state order). A derivation's
:data:`Place` is that order's key: its cost, then its :data:`Path`, the
choices it made from the goal on (:attr:`cfgplan.planner.partial.Partial.path`).
Every strategy ranks by it:

- best-first search (:mod:`cfgplan.planner.search`) queues nodes by
  :func:`place`, a node's priority (cost so far plus a lower bound) for its cost;
- the greedy dive (:mod:`cfgplan.planner.dive`) takes children by :func:`place`;
- ``--all`` (:mod:`cfgplan.planner.enumerate`) sorts a cost window by place,
  each derivation's path stood for by its rank in the depth-first walk
  (the walk meets derivations in path order; an integer holds less);
- combinations of independent parts (:mod:`cfgplan.planner.combine`) and
  sequences of configurations (:mod:`cfgplan.planner.sequence`) are listed
  by :func:`merge`, each candidate carrying a place of its own kind: a
  combination's cost, then the choices below each choice item in the order
  the thesis meets them; a sequence's cost, then its steps' ranks, the first
  step first.

:func:`merge` is the one lazy k-best merge: a best-first listing of
candidates offered as it goes, where what a candidate offers never comes
before it.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterable, Iterator
from typing import Any, Protocol, TypeVar

from cfgplan.planner import clock

Path = tuple[int, ...]
"""The choices a derivation made, in the order it made them: the index of
each expansion taken among those of its item (4.5's backtracking order)."""

Place = tuple[float, Path]
"""Where a derivation is listed: cheaper first, then earlier in depth-first order."""


class _Ranked(Protocol):
    path: Path


def place(cost: float, node: _Ranked) -> Place:
    """The place of ``node`` (a derivation, complete or partial) at ``cost``:
    a partial node's at its priority is at most that of every derivation it
    completes to, as its path is a prefix of theirs."""
    return cost, node.path


class _Comparable(Protocol):
    def __lt__(self, other: Any, /) -> bool: ...


C = TypeVar("C", bound=_Comparable)


def merge(
    first: Iterable[C], offers: Callable[[C], Iterable[C]], listed: Callable[[C], bool]
) -> Iterator[C]:
    """The candidates reached from ``first`` through ``offers``, least first
    (a candidate compares by its place), those ``listed`` says are results.

    Requires that what a candidate offers never compares below it: then a
    candidate taken from the queue is the least of all still to come. Its
    offers are made only when the next one is asked for (after it is
    yielded, when it is a result), so ``-k 1`` makes no offer beyond the
    first result's. ``offers`` must offer a candidate once (an offer reached
    two ways is the caller's to drop)."""
    queue = list(first)
    heapq.heapify(queue)
    while queue:
        clock.check()
        candidate = heapq.heappop(queue)
        if listed(candidate):
            yield candidate
        for offered in offers(candidate):
            heapq.heappush(queue, offered)
