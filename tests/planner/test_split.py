"""Children priced from their parent's split (cfgplan.planner.split): never
past a child's cheapest completion, the same ranked lists with fewer
refinements, and the search started over when two nodes of one canonical
form were taken out of depth-first order."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from benchmarks.families import ecology, fusion, media_tight, wall
from cfgplan.configuration.model import Configuration
from cfgplan.planner import plan, search
from cfgplan.planner.bound import Bound
from cfgplan.planner.ground import Grounder
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.partition import Partition
from cfgplan.planner.plan import Run
from cfgplan.planner.successors import successors
from tests.planner.test_bound import least_completion
from tests.planner.test_room import search_tree
from tests.planner.test_scale import problem_of


@pytest.mark.parametrize(
    "texts",
    [media_tight(4, 2, 1), fusion(4, 3, 4, 3), ecology(6, 2, 1)],
    ids=["media-tight-4", "fusion-4", "ecology-6"],
)
def test_a_child_priced_from_its_parents_split_costs_at_least_that(
    texts: tuple[str, str],
) -> None:
    """Below each of the first 80 nodes, every child's price from the node's
    split is at most its cheapest completion (none where the media cannot
    carry its expansion), and somewhere above the first bound, which the
    child would otherwise be queued with until it is refined."""
    problem = problem_of(texts)
    grounder, bound = Grounder(problem.task), Bound(problem.task)
    partition = Partition(grounder)
    above = 0
    for node in search_tree(problem, 80):
        total, split = partition.split(node, bound.certain_agents(node))
        assert total is not None and split is not None
        for child in successors(grounder, node):
            if not isinstance(child, Partial):
                continue
            price = split.prices[child.path[len(node.path)]]
            truth = least_completion(grounder, child)
            if price == float("inf"):
                assert truth is None
                continue
            priced = node.cost + split.rest + price
            if truth is not None:
                assert priced <= truth + 1e-9
            first = bound.estimate(child)
            above += first is not None and priced > child.cost + first + 1e-9
    assert above > 0


@pytest.mark.parametrize(
    "texts",
    [ecology(18, 3, 3), fusion(4, 3, 4, 3), fusion(8, 3, 6, 6), media_tight(6, 4, 4)],
    ids=["ecology-18", "fusion-4", "fusion-8", "media-tight-6"],
)
def test_pricing_children_from_splits_changes_no_ranked_list(texts: tuple[str, str]) -> None:
    """The 20 cheapest, costs, identities and derivation numbers, with the
    children priced from their parents' splits and without
    (``SearchOptions.splits``): the same, with fewer refinements (the plain
    search, not the parts')."""
    problem = problem_of(texts)
    with_splits = Run(
        problem.task, problem.goal_call, limit=20, options=SearchOptions(components=False)
    )
    configs = list(with_splits)
    problem = problem_of(texts)  # a new task: its bounds are made anew
    without = Run(
        problem.task,
        problem.goal_call,
        limit=20,
        options=SearchOptions(components=False, splits=False),
    )
    assert [(c.cost, c.identity(), c.derivation) for c in configs] == [
        (c.cost, c.identity(), c.derivation) for c in without
    ]
    assert with_splits.strategy.pricer.tried < without.strategy.pricer.tried
    assert with_splits.stats.nodes == without.stats.nodes


def test_a_search_started_over_lists_what_one_search_lists(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Told after its third configuration that two nodes of one canonical form
    were taken out of depth-first order (which pricing children from splits
    can cause, and no family or generated problem was seen to), the search
    starts over without the splits and skips what it listed: the list, its
    derivation numbers and the repeats counted are those of one search."""
    problem = problem_of(wall(3, 4, 3))  # repeats: distinct lists skip some derivations
    expected, run = plan(problem.task, problem.goal_call, limit=40)
    original = search.BestFirst._search
    told: list[bool] = []

    def interrupted(self: search.BestFirst, start: float) -> Iterator[Configuration]:
        for index, config in enumerate(original(self, start)):
            yield config
            if index == 2 and not told:
                told.append(True)
                self.pricer.lifted = max(self.pricer.lifted, 1)
                raise search._Twins

    monkeypatch.setattr(search.BestFirst, "_search", interrupted)
    again, restarted = plan(problem.task, problem.goal_call, limit=40)
    assert told
    assert run.stats.duplicates > 0
    assert [(c.cost, c.identity(), c.derivation) for c in again] == [
        (c.cost, c.identity(), c.derivation) for c in expected
    ]
    counted = ("derivations", "duplicates", "rejected")
    assert [getattr(restarted.stats, k) for k in counted] == [
        getattr(run.stats, k) for k in counted
    ]
    assert restarted.strategy.pricer.split is None
