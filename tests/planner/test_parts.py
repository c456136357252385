"""The least parts that may share names can cost together
(cfgplan/planner/bound.py): the groups of parts linked by shared names,
each counted once at its dearest part, found however wide the parts are."""

from __future__ import annotations

from collections.abc import Hashable, Set

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cfgplan.planner.bound import GROUPS, MOST_WIDE, WIDE, _grouped, _many, least, own_part
from tests.planner.problems import PROPERTY


def groups_by_pairs(parts: list[tuple[Set[Hashable], float]]) -> float:
    """The same sum found the plain way: join every two parts that share a
    name until nothing changes, then add each group's dearest part."""
    groups = [({i}, set(names)) for i, (names, _) in enumerate(parts) if names]
    merged = True
    while merged:
        merged = False
        for a in range(len(groups)):
            for b in range(a + 1, len(groups)):
                if groups[a][1] & groups[b][1]:
                    groups[a] = (groups[a][0] | groups[b][0], groups[a][1] | groups[b][1])
                    del groups[b]
                    merged = True
                    break
            if merged:
                break
    alone = sum(cost for names, cost in parts if not names)
    return alone + sum(max(parts[i][1] for i in members) for members, _ in groups)


def part_lists(
    narrow_names: int, narrow_most: int, costs: st.SearchStrategy[float], most: int
) -> st.SearchStrategy[list[tuple[frozenset[int], float]]]:
    """Lists of up to ``most`` parts, each narrow (up to ``narrow_most`` of
    the names 0..``narrow_names``) or wide (more than WIDE names), at ``costs``."""
    names = st.one_of(
        st.frozensets(st.integers(0, narrow_names), max_size=narrow_most),
        st.frozensets(st.integers(0, WIDE + 40), min_size=WIDE + 1, max_size=WIDE + 20),
    )
    return st.lists(st.tuples(names, costs), max_size=most)


def names(prefix: str, count: int) -> frozenset[Hashable]:
    return frozenset(f"{prefix}{i}" for i in range(count))


def test_a_wide_part_joins_the_narrow_parts_it_shares_with_before_and_after_it() -> None:
    wide = names("n", WIDE + 10)
    parts: list[tuple[Set[Hashable], float]] = [
        (frozenset({"n3"}), 5.0),  # shares with the wide part, met before it
        (wide, 4.0),
        (frozenset({"n7", "x"}), 9.0),  # after it
        (frozenset({"x", "y"}), 2.0),  # through the part before
        (frozenset({"z"}), 1.0),  # alone
        (own_part("c"), 3.0),
        (frozenset(), 0.5),
    ]
    assert least(parts) == 9.0 + 1.0 + 3.0 + 0.5 == groups_by_pairs(parts)


def test_wide_parts_past_the_most_are_filed_name_by_name_and_still_met() -> None:
    many = MOST_WIDE + 4
    parts: list[tuple[Set[Hashable], float]] = [
        (names(f"w{k}-", WIDE + 1) | {f"link{k}"}, float(k + 1)) for k in range(many)
    ]
    parts.append((frozenset({"link0", f"link{many - 2}"}), 0.0))  # joins the first and a late one
    # Every part its own group but the first, which counts in the late one's.
    assert _many(parts) == least(parts) == sum(range(2, many + 1)) == groups_by_pairs(parts)


@pytest.mark.quick(30)
@PROPERTY
@given(part_lists(WIDE + 40, 4, st.sampled_from([0.0, 0.5, 1.0, 2.0, 3.0, 10.0]), 30))
def test_least_is_the_sum_of_the_groups_dearest_parts(
    parts: list[tuple[frozenset[int], float]],
) -> None:
    given_parts: list[tuple[Set[Hashable], float]] = list(parts)
    assert least(given_parts) == groups_by_pairs(given_parts)


@pytest.mark.quick(30)
@PROPERTY
@given(part_lists(40, 3, st.floats(0.0, 100.0), 3 * GROUPS))
def test_meeting_groups_and_filing_names_give_one_float(
    parts: list[tuple[frozenset[int], float]],
) -> None:
    """While at most GROUPS groups are apart least() meets each part with
    the groups so far, past it it files their names: both find the same
    groups and add their costs in one order, so any costs (not only the
    exact halves above) give one float; with fewer groups, meeting them
    never gives up."""
    given_parts: list[tuple[Set[Hashable], float]] = list(parts)
    met = _grouped(given_parts, len(given_parts))
    assert met == _many(given_parts) == least(given_parts)
    assert _grouped(given_parts, GROUPS) in (met, None)


def test_more_groups_than_the_cap_are_found_by_filing_names() -> None:
    """Past GROUPS groups apart, meeting each part with the groups gives up
    and least() files the names instead: the same sum. One part then joins
    the first and the last group (a group is found whole either way)."""
    parts: list[tuple[Set[Hashable], float]] = [
        (frozenset({f"n{i}"}), float(i)) for i in range(GROUPS + 4)
    ]
    parts.append((frozenset({"n0", f"n{GROUPS + 3}"}), 0.5))
    assert _grouped(parts, GROUPS) is None
    assert _grouped(parts, len(parts)) == _many(parts) == least(parts) == groups_by_pairs(parts)
    assert least(parts) == sum(range(1, GROUPS + 4))  # n0's part counts in the last one's group
