"""Costs carried from one node to the next (cfgplan.planner.carry): at every
node a search refines, the partitioned bound and its split are the very
floats a fresh computation gives, and carrying leaves the ranked list as it
was."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import pytest

from benchmarks.families import chain, ecology, fusion, media_tight, relay, wall
from cfgplan.planner.bound import Bound
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partition import CARRY_FROM, Partition
from cfgplan.planner.plan import Run, parts
from cfgplan.problem import Problem
from tests.planner.test_room import search_tree
from tests.planner.test_scale import problem_of
from tests.planner.test_thesis import problem

FAMILIES = {
    "ecology-18": ecology(18, 3, 3),
    "media-tight-8": media_tight(8, 3, 2),  # media: the load changes
    "fusion-4": fusion(4, 3, 4, 3),
    "wall-3": wall(3, 4, 3),
    "relay-4": relay(4, 4, 3),
    "chain-8": chain(8),
}
THESIS = {
    "cross-door-4.6-media": ("cross-door/domain.lisp", "cross-door/state-4.6-media.lisp"),
    "carry-bar-6.3.2": ("carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp"),
    "build-wall-6.4": ("build-wall/domain.lisp", "build-wall/state-6.4.lisp"),
}


def _problem(name: str) -> Problem:
    if name in FAMILIES:
        return problem_of(FAMILIES[name])
    return problem(*THESIS[name])


def _checked(partition: Partition, fresh: Partition, tally: dict[str, int]) -> Callable[..., Any]:
    """``partition.split``, compared with ``fresh``'s at every call."""
    split, start = partition.split, partition.carry.start

    def carried_start(*args: Any) -> dict[int, float]:
        memo = start(*args)
        tally["carried"] += len(memo)
        return memo

    def checked(node: Any, certain: frozenset[str], apart: bool = True) -> Any:
        got = split(node, certain, apart)
        assert got == fresh.split(node, certain, apart), node.path
        tally["nodes"] += 1
        return got

    partition.carry.start = carried_start  # type: ignore[method-assign,assignment]
    return checked


@pytest.mark.parametrize("name", [*THESIS, "media-tight-8", "relay-4"])
def test_carried_across_the_tree_as_priced_afresh(name: str) -> None:
    """Nodes taken breadth first (far apart, unlike the search's), each
    starting from the costs of the one before: the same bound and split as
    a partition that never carries."""
    p = _problem(name)
    grounder, bound = Grounder(p.task), Bound(p.task)
    carrying, fresh = Partition(grounder), Partition(grounder)
    carrying.carry_from, fresh.carry_from = 0, sys.maxsize
    tally = {"nodes": 0, "carried": 0}
    split = _checked(carrying, fresh, tally)
    for node in search_tree(p, 300):
        split(node, bound.certain_agents(node))
    assert tally["nodes"] >= 5 and tally["carried"] > 0, tally


@pytest.mark.parametrize("name", list(FAMILIES))
def test_carried_costs_are_those_priced_afresh(name: str) -> None:
    """Carrying at every node, however shallow its items: each refinement's
    bound and split equal those of a partition that never carries (exactly:
    a bound a hair above a completion's cost would prune it), and the ten
    cheapest are those listed without carrying."""
    ranked = []
    for carry_from in (0, sys.maxsize):
        p = _problem(name)
        grounder, _, partition = parts(p.task)
        partition.carry_from = carry_from
        tally = {"nodes": 0, "carried": 0}
        if carry_from == 0:
            fresh = Partition(grounder)
            fresh.carry_from = sys.maxsize
            partition.split = _checked(partition, fresh, tally)  # type: ignore[method-assign]
        configs = list(Run(p.task, p.goal_call, limit=10))
        ranked.append([(c.cost, c.derivation, c.functionalities) for c in configs])
        if carry_from == 0:
            assert tally["nodes"] > 0 and tally["carried"] > 0, tally
    assert ranked[0] == ranked[1]


def test_shallow_items_are_priced_afresh() -> None:
    """Fusion's items are a piece from a few versions each: no node carries."""
    p = problem_of(fusion(4, 3, 4, 3))
    partition = parts(p.task)[2]
    assert partition.carry_from == CARRY_FROM
    list(Run(p.task, p.goal_call, limit=3))
    assert partition.carry._last is None
