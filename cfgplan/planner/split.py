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

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cfgplan.planner.room import Load, Need

if TYPE_CHECKING:
    from cfgplan.planner.partition import Instance, Option
    from cfgplan.planner.prices import Prices

Fits = Callable[[tuple[Need, ...], Load], bool]


@dataclass(frozen=True, slots=True)
class Split:
    """A node's bound without its top item (``rest``), and the price of each
    of the top item's expansions by choice number, as
    :func:`cfgplan.planner.successors.successors` numbers them (infinite
    where the media cannot carry it, :mod:`cfgplan.planner.room`)."""

    rest: float
    prices: dict[int, float]


def split_at(
    top: Instance, rest: float, memo: dict[int, float], prices: Prices, fits: Fits
) -> Split | None:
    """The split of a node whose top item is ``top`` (None: a functionality),
    from the memo of its refinement."""
    if top.functionality:
        return None
    return Split(rest, {option.choice: price(option, memo, prices, fits) for option in top.options})


def price(option: Option, memo: dict[int, float], prices: Prices, fits: Fits) -> float:
    """What ``option`` costs at ``prices``, added up in the order
    :meth:`cfgplan.planner.partition.Partition._least` adds it (the same
    float, so that the child's bound is never above a completion's cost)."""
    if option.needs and not fits(option.needs, prices.load):
        return float("inf")
    cost = 0.0
    for child in option.child_keys:
        cost += memo[child]
    for own in option.channels:
        cost += prices.channel(own)
    for agent in option.agents:
        cost += prices.agent(agent)
    return cost
