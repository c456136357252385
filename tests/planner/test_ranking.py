"""The listing order and the one lazy k-best merge (cfgplan.planner.search),
which lists the combinations of independent parts (combine.py) and the
sequences of configurations (sequence.py)."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

from hypothesis import given
from hypothesis import strategies as st

from cfgplan.planner.partial import root
from cfgplan.planner.search import merge, place

Offer = tuple[int, tuple[int, ...]]  # (sum, index in each list)


def _product(lists: list[list[int]], asked: list[Offer] | None = None) -> Iterator[Offer]:
    """The sums of one item of each sorted list, least first, as combine.py
    offers them: taking a combination offers each list's next item in its place."""
    start = tuple(0 for _ in lists)
    offered = {start}

    def offers(offer: Offer) -> Iterator[Offer]:
        if asked is not None:
            asked.append(offer)
        at = offer[1]
        for p in range(len(at)):
            then = (*at[:p], at[p] + 1, *at[p + 1 :])
            if then[p] < len(lists[p]) and then not in offered:
                offered.add(then)
                yield sum(lists[q][i] for q, i in enumerate(then)), then

    return merge([(sum(x[0] for x in lists), start)], offers, lambda _: True)


@given(st.lists(st.lists(st.integers(0, 9), min_size=1, max_size=4), min_size=1, max_size=3))
def test_merge_lists_every_combination_once_in_its_place(raw: list[list[int]]) -> None:
    lists = [sorted(x) for x in raw]
    every = sorted(
        (sum(lists[p][i] for p, i in enumerate(at)), at)
        for at in itertools.product(*(range(len(x)) for x in lists))
    )
    assert list(_product(lists)) == every


def test_merge_makes_no_offer_before_the_next_candidate_is_asked_for() -> None:
    """``-k 1`` searches no part for a second configuration."""
    asked: list[Offer] = []
    listing = _product([[1, 2], [3, 4]], asked)
    assert next(listing) == (4, (0, 0))
    assert asked == []
    assert next(listing) == (5, (0, 1))  # ties by the indices, the first list's first
    assert asked == [(4, (0, 0))]


def test_merge_lists_only_what_is_listed_but_ranks_everything() -> None:
    """As sequence.py queues offers (not listed) beside sequences (listed)."""

    # Candidates (price, name); an offer "o<n>" priced under 6 offers the
    # result "r<n>" at its price + 1 and the next offer at its price + 2.
    def offers(c: tuple[int, str]) -> Iterator[tuple[int, str]]:
        price, name = c
        if name.startswith("o") and price < 6:
            yield price + 1, "r" + name[1:]
            yield price + 2, "o" + str(int(name[1:]) + 1)

    listed = list(merge([(0, "o0")], offers, lambda c: c[1].startswith("r")))
    assert listed == [(1, "r0"), (3, "r1"), (5, "r2")]


def test_a_place_is_the_cost_then_the_path() -> None:
    node = root(("goal",))
    assert place(3.0, node) == (3.0, node.path)
    cheaper, earlier = (2.0, (5,)), (3.0, (0, 1))
    assert cheaper < earlier < (3.0, (0, 2)) < (3.0, (1,))
