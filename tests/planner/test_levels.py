"""Costs and bounds at levels (cfgplan.planner.costs): equal decimals rank
equal however their floats were summed, and a bound never ranks above a
cost it bounds."""

from __future__ import annotations

import random
from fractions import Fraction

from hypothesis import given
from hypothesis import strategies as st

from cfgplan.configuration.cost import Weights
from cfgplan.planner.costs import Levels, level, unit_of
from tests.planner.problems import PROPERTY, load_text

SWITCHED = """\
(make-functionality :name '(f ?r) :precond '((robot ?r)) :out '((d ?r)) :cost 4000000)
(make-config-method :name '(job ?r) :precond '((robot ?r)) :body '((?a (f ?r))))
"""
DECIMALS = [0.1, 0.2, 0.3, 0.7, 1.1, 2.5, 3.3, 10.7, 0.05, 12.25]


def test_the_unit_is_the_greatest_common_divisor_of_the_decimals() -> None:
    assert unit_of([10, 3, 1, 1, 10]) == 1  # the thesis's weights
    assert unit_of([10.7, 3.3, 1.1, 1, 10]) == Fraction(1, 10)
    assert unit_of([10, 4, 2, 2]) == 2
    assert unit_of([0.25, 0.5, 1]) == Fraction(1, 4)
    assert unit_of([0, 0]) == 1  # every cost is 0
    assert unit_of([1 / 3]) is None  # no short decimal: 0.3333333333333333
    assert unit_of([1e-7]) is None  # more than six decimals
    assert unit_of([1e6, 1e-6]) is None  # 1e12 units: a float sum of them errs by units
    assert unit_of([1e8, 1]) == 1
    assert unit_of([1e15, 1]) == 1  # whole: float sums exact below 2**53


def test_floats_of_one_decimal_rank_alike() -> None:
    tenths = Levels(Fraction(1, 10))
    assert 0.1 + 0.2 != 0.3
    assert tenths.cost(0.1 + 0.2) == tenths.cost(0.3) == 0.3
    assert tenths.bound(0.1 + 0.2) == 0.3  # an exact bound, a bit above in floats
    assert tenths.bound(0.25) == 0.3  # rounded up: every cost is a multiple of 0.1
    assert Levels(None).cost(0.1 + 0.2) == level(0.3) == 0.3
    assert Levels(None).bound(0.1 + 0.2) == 0.3
    assert Levels(Fraction(1)).bound(863.2) == 864.0


def test_a_switch_weight_joins_the_unit() -> None:
    even = Weights(robot=10, global_=4, local=2, functionality=2, device=10)
    task = load_text(SWITCHED, "(state (robot X))\n\n(goal (job X))\n", even).task
    assert task.levels == Levels(Fraction(2))
    assert task.costs.levels(0) == Levels(Fraction(2))  # no switch: costs as they were
    assert task.costs.levels(3) == Levels(Fraction(1))
    assert task.costs.levels(0.5) == Levels(Fraction(1, 2))
    assert task.costs.levels(1 / 3) == Levels(None)
    assert task.costs.levels(1e-6) == Levels(None)  # 4e6 is 4e12 of it: past the range


def test_an_edge_above_a_level_is_below_the_next() -> None:
    assert Levels(Fraction(1)).above(864.0) == 864.5
    assert Levels(Fraction(1, 10)).above(919.7) == 919.75
    big = 3e9 + 0.5  # 1e-9 above it is no other float
    assert big < Levels(None).above(big) < level(big + 0.1)  # the next level: 3000000000.6


@PROPERTY
@given(
    st.lists(st.sampled_from(DECIMALS), min_size=1, max_size=400),
    st.integers(0, 2**32),
    st.booleans(),
)
def test_sums_in_any_order_rank_alike_and_bounds_never_pass_them(
    parts: list[float], seed: int, units: bool
) -> None:
    """A cost summed in two orders, and a lower bound summed in a third from
    shares of the same parts (w/3 three times for w, as the partition bound
    divides a shared cost)."""
    levels = Levels(unit_of(DECIMALS) if units else None)
    shuffled = parts[:]
    random.Random(seed).shuffle(shuffled)
    forward, backward = sum(parts), sum(shuffled)
    assert levels.cost(forward) == levels.cost(backward)
    shares = [w / 3 for w in shuffled for _ in range(3)]
    assert levels.bound(sum(shares)) == levels.cost(forward)  # exact: at the cost's level
    assert levels.bound(sum(shares[:-1])) <= levels.cost(forward)
    exact = sum(Fraction(repr(w)) for w in parts)
    assert levels.cost(forward) == float(exact)  # the decimal itself


def test_whole_bounds_of_huge_weights_stay_below_the_cost() -> None:
    """Weights up to 1e15 are allowed: a float sum of shares near 1e16 errs by
    more than the absolute hair of 1e-6 (its relative part covers it)."""
    w = 999_999_999_999_993.0
    shares = [w / 7] * 7 * 10
    whole = Levels(Fraction(1))
    assert sum(shares) > w * 10  # the float sum passes the true cost by 6
    assert whole.bound(sum(shares)) <= whole.cost(w * 10)
