"""Children priced from their parent's split (cfgplan.planner.partition): never
past a child's cheapest completion, the same ranked lists with fewer
refinements, and a node taken after its twin of one canonical form that it
comes before in depth-first order superseding that twin."""

from __future__ import annotations

from itertools import islice
from pathlib import Path

import pytest

from benchmarks.families import ecology, fusion, media_tight, wall
from cfgplan.planner import search
from cfgplan.planner.bound import Bound
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import successors
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.partition import Partition
from cfgplan.planner.plan import Run, growing
from cfgplan.problem import load
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


REPRO = Path(__file__).resolve().parents[1] / "data" / "repros" / "k-not-prefix-of-all"


@pytest.mark.parametrize("limit", [5, 6, 7])
def test_a_twin_taken_out_of_order_is_superseded_and_the_list_is_one_searchs(limit: int) -> None:
    """On the issue-35 repro (from its fifth configuration on) the stronger
    bound, tried and given up, has priced a node above its twin of one
    canonical form that comes later in depth-first order, so that the twin
    is taken first: the earlier node
    supersedes it when taken (search.py, ``BestFirst._supersede``), and the
    search goes on without starting over. The list, its derivation numbers
    and the repeats and rejections counted are those of the search priced by
    the first bound alone (``warm`` never reached), where twins are priced
    alike and never taken out of order."""

    def searched(warm: int) -> tuple[list[tuple[float, object, int]], Run]:
        problem = load(REPRO / "labels-domain.lisp", REPRO / "labels-state.lisp")
        options = SearchOptions(components=False, warm=warm)
        run = Run(problem.task, problem.goal_call, limit=limit, options=options)
        return [(c.cost, c.identity(), c.derivation) for c in run], run

    found, run = searched(SearchOptions().warm)
    expected, plain = searched(warm=10**9)
    assert isinstance(run.strategy, search.BestFirst)
    assert isinstance(plain.strategy, search.BestFirst)
    assert run.strategy.superseded > 0 and run.strategy.pricer.tried > 0
    assert plain.strategy.superseded == 0 and plain.strategy.pricer.tried == 0
    assert found == expected
    counted = ("derivations", "duplicates", "rejected")
    assert [getattr(run.stats, k) for k in counted] == [getattr(plain.stats, k) for k in counted]


def test_what_a_superseded_node_left_open_is_dropped_and_its_forms_reopened() -> None:
    """The mechanism alone (no generated problem was seen to take a twin out
    of order with its expansion's nodes still open, so it is driven by hand):
    once an expanded node is superseded (``BestFirst._supersede``), no node
    below it is taken any more, so no configuration derived below it is
    listed, and the canonical forms it closed count as open again."""
    problem = problem_of(wall(3, 4, 3))

    def searched() -> search.BestFirst:
        grower, pricer = growing(problem.task, SearchOptions(components=False))
        return search.BestFirst(grower, pricer, problem.goal_call)

    plain = searched()
    paths = []
    for _ in islice(plain, 12):
        assert plain.last is not None
        paths.append(plain.last.path)
    driven = searched()
    listed = iter(driven)
    done: list[tuple[int, ...]] = []
    later: tuple[int, ...] | None = None
    target: tuple[int, ...] = ()
    while later is None:  # list until a later configuration's branch is expanded
        next(listed)
        assert driven.last is not None
        done.append(driven.last.path)
        expanded = set(driven._closed.values())
        for path in paths[len(done) :]:
            # The shortest prefix of its derivation expanded so far that no
            # configuration listed shares: the search would go on below it.
            mine = (path[:n] for n in range(1, len(path)))
            found = [p for p in mine if p in expanded and all(d[: len(p)] != p for d in done)]
            if found:
                later, target = found[0], path
                break
    driven._supersede(later)
    assert driven.superseded == 1
    assert driven._below_superseded(later) and driven._below_superseded(target)
    assert not any(driven._below_superseded(d) for d in done)
    closed_below = [p for p in driven._closed.values() if p[: len(later)] == later]
    assert closed_below and all(driven._below_superseded(p) for p in closed_below)
    # The plain search lists ``target``, below ``later``, among the next ones;
    # the driven one lists none of them.
    assert paths.index(target) < len(done) + 6
    for _ in islice(listed, 6):
        assert driven.last is not None
        assert driven.last.path[: len(later)] != later
