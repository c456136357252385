"""What things cost and how costs are ranked: every pricing rule of the planner,
and the levels costs and bounds are compared at.

How costs are ranked: the levels a cost and a lower bound are compared at.

A cost is a float sum (thesis 3.5), and two configurations of one cost
summed in another order (``0.1 + 0.2`` against ``0.2 + 0.1`` and the like)
may differ in the last bit. Ranked by the floats, the one that happens to be
a bit less would come first, not the first in the thesis's depth-first order
(6.3.2); and an exact bound may come out a bit above the cost it bounds.
So costs and bounds are ranked at *levels*:

- when every weight and ``:cost`` is a short decimal (the usual case), every
  cost is a whole multiple of their greatest common divisor, the *unit* (1
  for the thesis's weights, 0.1 for weights such as 1.1 and 3.3): a cost
  ranks as the multiple it is, and a bound rounds up to the next multiple
  (less a hair for the float error of its sum);
- otherwise (reliability adds logarithms, a value has more than six
  decimals, or a fractional unit is too fine for the largest value,
  :data:`RANGE`) a cost ranks as its value to :data:`SIGNIFICANT`
  significant digits, and a bound as the level of its value less
  :data:`MARGIN`.

A bound's level is never above the level of a cost it bounds, and costs that
are equal in decimals rank equal where there is a unit. Without one, two
equal costs whose float sums fall either side of an eleventh digit's
rounding edge rank a digit apart (rare: sums err by about 1e-15 of
themselves, a digit is 1e-11). Whole costs below 2**53 are exact floats and
keep their value.

What each part of a configuration costs (thesis 3.5, 7.2): every pricing
rule of the planner, in one place.

A configuration costs ``10·robots + 3·global + local + functionalities``
with the thesis's weights (:class:`cfgplan.configuration.cost.Weights`): an
agent's weight (a robot's, or a device's for an agent the state declares
``(device X)``), each channel's weight by its kind, each functionality's
``:cost`` or the functionality weight; with ``reliability=W``, ``W·(−ln p)``
more for each functionality of reliability p and for each global channel
between two robots, p that of the most reliable medium between them. The
search adds these up as it places functionalities and channels
(:mod:`cfgplan.planner.partial`, :mod:`cfgplan.planner.partial`), the bounds
add up the least of them a node must still pay (:mod:`cfgplan.planner.bound`,
:mod:`cfgplan.planner.bound`, :mod:`cfgplan.planner.graph`), the solver
writes them into its program (:mod:`cfgplan.planner.solver`), and the unit
costs are ranked by is the greatest common divisor of them all
(:meth:`Costs.levels`). Each reads them here: changing what something costs
is a change to this module. (The independent admissibility checker,
:mod:`cfgplan.configuration.admissible`, keeps its own copy on purpose: it
checks the planner's answers.)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Protocol

from cfgplan.configuration.cost import Weights

SIGNIFICANT = 11
"""Digits to which costs with no unit are ranked (:func:`level`)."""

MARGIN = 2e-12
"""What a bound on costs with no unit is lowered by, relative to its size,
before :func:`level`: more than the float error of the sums of a bound and of
a cost (about 1e-13 of them), much less than half a digit of
:data:`SIGNIFICANT` (5e-12 of them at least)."""

DECIMALS = 6
"""Decimals a weight or ``:cost`` may have for costs to have a unit."""

RANGE = 1e8
"""How many units the largest weight or ``:cost`` may be for fractional
costs to have a unit: a cost of ten thousand parts is then at most 1e12
units, which a float sum holds to a tenth of a unit (1e6 and 1e-6 have no
unit: their costs rank to :data:`SIGNIFICANT` digits). Whole values always
have one: their float sums are exact below 2**53."""

HAIR = 1e-6, 1e-9
"""What a bound is lowered by before it is rounded up to a multiple of the
unit: this many units, plus this much of itself (the float error of a sum
of thousands of shared costs grows with its size)."""


def level(cost: float) -> float:
    """A cost with no unit as it is ranked: to :data:`SIGNIFICANT` digits."""
    return float(f"{cost:.{SIGNIFICANT}g}")


def below(bound: float) -> float:
    """The level of a lower bound on costs with no unit: never above the level
    of a cost it bounds, though the float sums of both err (:data:`MARGIN`)."""
    return level(bound - MARGIN * abs(bound))


def unit_of(values: Iterable[float]) -> Fraction | None:
    """The greatest common divisor of ``values`` read as the decimals they
    are written in (a float's shortest form: 0.1 is 1/10); 1 when all are 0;
    None when one has more than :data:`DECIMALS` decimals, or the unit is a
    fraction and the largest is more than :data:`RANGE` units."""
    unit, largest = Fraction(0), Fraction(0)
    for value in values:
        exact = Fraction(repr(float(value)))
        if exact.denominator > 10**DECIMALS:
            return None
        unit, largest = _gcd(unit, exact), max(largest, exact)
    if not unit:
        return Fraction(1)
    return unit if unit.denominator == 1 or largest <= RANGE * unit else None


def _gcd(a: Fraction, b: Fraction) -> Fraction:
    return Fraction(
        math.gcd(a.numerator * b.denominator, b.numerator * a.denominator),
        a.denominator * b.denominator,
    )


@dataclass(frozen=True)
class Levels:
    """Costs and bounds as configurations (or sequences) are ranked by them."""

    unit: Fraction | None
    """Every cost is a whole multiple of it; None: costs have no unit."""
    _n: int = field(init=False, repr=False, compare=False)
    _d: int = field(init=False, repr=False, compare=False)
    _one: bool = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # The unit as integers n / d, and whether it is 1: used per node priced.
        n, d = (0, 1) if self.unit is None else (self.unit.numerator, self.unit.denominator)
        object.__setattr__(self, "_n", n)
        object.__setattr__(self, "_d", d)
        object.__setattr__(self, "_one", n == d == 1)

    def above(self, level: float) -> float:
        """An edge above ``level`` below every higher level: half a unit up,
        or the next float (levels of no unit are distinct floats)."""
        if self.unit is None:
            return math.nextafter(level, math.inf)
        return level + self._n / self._d / 2

    def cost(self, cost: float) -> float:
        """A cost's level: the multiple of the unit it is, or its value to
        :data:`SIGNIFICANT` digits."""
        if self._one:
            return float(round(cost))
        if self.unit is None:
            return level(cost)
        n, d = self._n, self._d
        return round(cost * d / n) * n / d

    def bound(self, bound: float) -> float:
        """A lower bound's level: never above the level of a cost it bounds."""
        if self._one:
            return float(math.ceil(bound - HAIR[0] - HAIR[1] * abs(bound)))
        if self.unit is None:
            return below(bound)
        n, d = self._n, self._d
        units = bound * d / n
        return math.ceil(units - HAIR[0] - HAIR[1] * abs(units)) * n / d


class Declared(Protocol):
    """What is read of a functionality schema
    (:class:`cfgplan.planner.task.FunctionalitySchema`)."""

    @property
    def cost(self) -> float | None: ...
    @property
    def reliability(self) -> float | None: ...


@dataclass(frozen=True, eq=False, repr=False)
class Costs:
    """The prices of one task's parts (:attr:`cfgplan.planner.task.Task.costs`)."""

    weights: Weights
    devices: frozenset[str]
    """Agents the state declares ``(device X)``: weighted as devices, not robots."""
    links: Mapping[tuple[str, str], float]
    """(sender, receiver) -> the most reliable medium's reliability (1 if unsaid)."""
    reliability: Mapping[tuple[str, ...], float]
    """Reliabilities of functionality instances that replace their schema's."""
    declared: tuple[float, ...]
    """Every functionality schema's ``:cost`` (those that have one)."""

    def functionality(self, schema: Declared, call: tuple[str, ...]) -> float:
        """The functionality's ``:cost``, else the functionality weight (3.5),
        plus ``W·(−ln p)`` for its reliability p when ``reliability=W``."""
        cost = schema.cost if schema.cost is not None else self.weights.functionality
        if self.weights.reliability:
            cost += self.weights.reliability * -math.log(self.reliability_of(schema, call))
        return cost

    def reliability_of(self, schema: Declared, call: tuple[str, ...]) -> float:
        """A functionality instance's reliability (7.2): the state's for the
        instance, else its schema's, else 1."""
        found = self.reliability.get(call)
        if found is not None:
            return found
        return schema.reliability if schema.reliability is not None else 1.0

    def channel(self, kind: str) -> float:
        """A channel's weight by its kind (3.5); :meth:`link` adds its media's."""
        return self.weights.global_ if kind == "global" else self.weights.local

    def link(self, sender: str, receiver: str) -> float:
        """``W·(−ln p)`` for a global channel between two robots: p is the most
        reliable medium from ``sender`` to ``receiver`` (1 when none says)."""
        if not self.weights.reliability or sender == receiver:
            return 0.0
        return self.weights.reliability * -math.log(self.links.get((sender, receiver), 1.0))

    def agent(self, agent: str) -> float:
        """What running something on ``agent`` costs: a robot's or a device's weight."""
        return self.weights.device if agent in self.devices else self.weights.robot

    def levels(self, *more: float) -> Levels:
        """How costs are ranked: by the unit
        every price above is a multiple of (and ``more``, e.g. a sequence's
        switch weight), unless reliability adds logarithms to them."""
        w = self.weights
        if w.reliability:
            return Levels(None)
        return Levels(
            unit_of([w.robot, w.device, w.global_, w.local, w.functionality, *more, *self.declared])
        )
