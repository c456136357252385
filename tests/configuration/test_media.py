"""Communication admissibility (4.6): assigning global channels to media
(cfgplan.configuration.media), against a brute force over every assignment."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from cfgplan.configuration.media import Demand, assign
from cfgplan.ir.model import Medium


def fits_somehow(demands: list[Demand | None], media: list[Medium]) -> bool:
    """Is there any assignment at all? Every channel tried on every medium."""
    needing = [d for d in demands if d is not None]
    for choice in itertools.product(range(len(media)), repeat=len(needing)):
        load = [0.0] * len(media)
        for d, j in zip(needing, choice, strict=True):
            if (media[j].sender, media[j].receiver) != (d.sender, d.receiver):
                break
            load[j] += d.bandwidth
        else:
            if all(x <= m.capacity for x, m in zip(load, media, strict=True)):
                return True
    return False


media_lists = st.lists(
    st.builds(
        Medium,
        type=st.just("wifi"),
        sender=st.sampled_from("AB"),
        receiver=st.sampled_from("CD"),
        capacity=st.sampled_from([0, 5, 10, 15, 20]),
    ),
    min_size=1,
    max_size=4,
)
demand_lists = st.lists(
    st.one_of(
        st.none(),
        st.builds(
            Demand,
            sender=st.sampled_from("AB"),
            receiver=st.sampled_from("CD"),
            bandwidth=st.sampled_from([0.0, 3.0, 5.0, 7.0, 10.0]),
        ),
    ),
    max_size=6,
)


@settings(max_examples=400, deadline=None, derandomize=True)
@given(demand_lists, media_lists)
def test_assigns_exactly_when_some_assignment_exists(
    demands: list[Demand | None], media: list[Medium]
) -> None:
    result = assign(demands, media)
    assert result.ok == fits_somehow(demands, media)
    if result.assignment is not None:
        assert set(result.assignment) == {i for i, d in enumerate(demands) if d is not None}
        load = [0.0] * len(media)
        for i, j in result.assignment.items():
            d = demands[i]
            assert d is not None and (media[j].sender, media[j].receiver) == (d.sender, d.receiver)
            load[j] += d.bandwidth
        assert all(x <= m.capacity for x, m in zip(load, media, strict=True))
    else:
        assert result.problem


def test_eleven_channels_into_ten_full_media_fail_at_once() -> None:
    """11 channels of 10 into 10 media of 10 took 101 s by trying
    orders; they need 110 where the media carry 100."""
    media = [Medium(type="wifi", sender="A", receiver="B", capacity=10)] * 10
    result = assign([Demand("A", "B", 10)] * 11, media)
    assert not result.ok
    assert "need 110, 10 more than it carries" in result.problem


def test_a_packing_first_fit_misses_is_found() -> None:
    """First fit, largest first, puts 5+4 in one medium and 3+3+3 in the other,
    with no room for the 2; the search finds 5+3+2 | 4+3+3."""
    media = [Medium(type="wifi", sender="A", receiver="B", capacity=10)] * 2
    demands: list[Demand | None] = [Demand("A", "B", b) for b in (5.0, 4.0, 3.0, 3.0, 3.0, 2.0)]
    result = assign(demands, media)
    assert result.assignment is not None
    loads = [0.0, 0.0]
    for i, j in result.assignment.items():
        d = demands[i]
        assert d is not None
        loads[j] += d.bandwidth
    assert loads == [10.0, 10.0]


def test_many_media_of_one_size_are_one_choice() -> None:
    """Interchangeable media: a refusal that order-search would take 30! tries for."""
    media = [Medium(type="wifi", sender="A", receiver="B", capacity=7)] * 30
    demands: list[Demand | None] = [Demand("A", "B", 4)] * 31
    assert not assign(demands, media).ok  # 31 × 4 = 124 ≤ 210, but one 4 per medium fits
