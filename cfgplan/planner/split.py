"""The partitioned bound of a node taken apart at its top item, to price the
node's children before they are refined.

A node expands its top item next (4.5 step 3), one child per expansion. The
partitioned bound (:mod:`cfgplan.planner.partition`) of the node is the
node's cost plus the sum, over its pending items, of each item's cheapest
derivation at the node's prices. Any completion in which the top item takes
expansion ``k`` pays for that item at least expansion ``k``'s price at those
same prices (its own channels and agents, and its children's cheapest), so
the partition argument bounds it by the node's cost plus ``rest`` (the sum
without the top item) plus that price: a bound for child ``k`` and all it
settles into, got from the node's own refinement, without pricing the child.

A child whose expansion costs more than the cheapest is so priced above its
parent, and taken only when the search gets that far: most are never
refined. The bound depends on the parent, not on the child alone, so two
nodes reached by different choices with one canonical form may be priced
apart; :class:`cfgplan.planner.search.BestFirst` watches for that.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from cfgplan.planner.graph import Instance


class Split(NamedTuple):
    """A node's bound without its top item (``rest``), and the price of each
    of the top item's expansions by choice number, as
    :func:`cfgplan.planner.successors.successors` numbers them (infinite
    where the media cannot carry it, :mod:`cfgplan.planner.room`)."""

    rest: float
    prices: dict[int, float]


def split_at(top: Instance, rest: float, priced: Sequence[float]) -> Split:
    """The split of a node whose top item is the method instance ``top``,
    its expansions ``priced`` in option order by its refinement
    (:class:`cfgplan.planner.least.Least`: each price the one the
    refinement took the cheapest of, so that a child's bound is never above
    a completion's cost)."""
    return Split(rest, {option.choice: priced[n] for n, option in enumerate(top.options)})
