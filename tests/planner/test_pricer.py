"""The stronger bound is given up where it does not pay (cfgplan/planner/pricer.py),
and giving it up never changes what is found."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.families import chain, ecology, fusion, gateway, wall
from cfgplan.planner.bound import Estimator, Together
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.plan import Run
from cfgplan.problem import load
from tests.planner.test_scale import problem_of


def _run(texts: tuple[str, str], limit: int, **tuned: int) -> tuple[list[tuple[float, str]], Run]:
    problem = problem_of(texts)  # the plain search, whose bounds these tests watch
    options = SearchOptions(components=False, **tuned)
    run = Run(problem.task, problem.goal_call, limit=limit, options=options)
    found = [(c.cost, str(sorted(map(str, c.functionalities)))) for c in run]
    return found, run


def test_the_partition_bound_is_given_up_where_it_never_pays_and_kept_where_it_does() -> None:
    """On wall K=6 N=20 L=8 it seldom raises a priority and is below the first
    bound on most nodes: dropped after ``trial`` refinements. On chain D=8 the
    first bound is exact (it counts each level's least total,
    ``Summary.together``: test_bound.py), so the stronger one never raises a
    priority either, but it is at least the first every time: kept, for
    ``rely`` to drop the first (priced from its last evaluation, it is the
    cheaper there). On fusion M=8 it raises nearly every one: kept. All
    tried from the first node. (On wall K=3 N=4 L=3 it pays since it prices
    channels with one end open by that end.)"""
    _, on_wall = _run(wall(6, 20, 8), 1, warm=0)
    _, on_chain = _run(chain(8), 1, warm=0)
    _, on_fusion = _run(fusion(8, 3, 6, 6), 1, warm=0)
    assert on_wall.strategy.pricer.refine is None
    chain_pricer = on_chain.strategy.pricer
    assert chain_pricer.refine is not None
    assert chain_pricer.raised == 0 and chain_pricer.dominated == chain_pricer.tried > 4
    assert on_fusion.strategy.pricer.refine is not None


def test_dropping_the_first_bound_keeps_the_open_nodes_priorities() -> None:
    """On chain D=60 the first bound is dropped (``rely``) with dozens of
    nodes open, the siblings of the levels above, each priced above the
    frontier by its parent's split. Priced again by feasibility alone, each
    fell to its cost and was taken and refined at once (133 refinements for
    62 nodes taken); keeping their priorities, none is refined that is not
    taken (the search goes straight down), and it finds the same."""
    found, run = _run(chain(60), 1)
    pricer = run.strategy.pricer
    # Asserted on plain values: a failed assertion on the pricer's bound
    # methods would show their reprs, the search's whole state.
    dropped = pricer.heuristic is pricer.feasible
    refined, taken = pricer.tried, run.stats.nodes
    assert dropped
    assert refined <= taken == 62
    kept, _ = _run(chain(60), 1, rely=10**9)  # the first bound never dropped
    assert found == kept


@pytest.mark.parametrize(
    "texts", [wall(3, 4, 3), chain(8), ecology(6, 2, 1)], ids=["wall", "chain", "ecology"]
)
def test_giving_the_bound_up_changes_nothing_found(texts: tuple[str, str]) -> None:
    """The ten cheapest, with the bound kept throughout (``trial`` never reached)
    and with the usual rule, are the same configurations at the same costs."""
    usual, _ = _run(texts, 10, warm=0)
    kept, run = _run(texts, 10, warm=0, trial=10**9)
    assert run.strategy.pricer.refine is not None
    assert [cost for cost, _ in usual] == [cost for cost, _ in kept]
    last = usual[-1][0]  # ties at the last cost may be cut differently
    assert sorted(c for c in usual if c[0] < last) == sorted(c for c in kept if c[0] < last)


def test_a_small_search_never_tries_the_stronger_bound() -> None:
    """Build-wall (6.4) finds its cheapest configuration having priced fewer
    than ``warm`` nodes: the partition bound is not computed once; ecology N=18,
    larger, tries it."""
    domains = Path(__file__).resolve().parents[2] / "domains" / "build-wall"
    problem = load(domains / "domain.lisp", domains / "state-6.4.lisp")
    small = Run(problem.task, problem.goal_call, limit=1)
    assert [c.cost for c in small] == [53]
    assert small.strategy.pricer.settled < SearchOptions().warm
    assert small.strategy.pricer.tried == 0
    _, large = _run(ecology(18, 3, 3), 1)
    assert large.strategy.pricer.settled > SearchOptions().warm
    assert large.strategy.pricer.tried > 0


def _together(run: Run) -> Together:
    first = run.strategy.pricer.first
    assert isinstance(first, Estimator)
    return first.together


def test_the_together_least_cost_is_given_up_where_it_never_raises_the_first_bound() -> None:
    """The first bound's third least cost (functionalities and channels as
    one sum per item, ``Summary.together``) makes the bound exact on a deep
    chain: it raises the first estimates, so it is counted to the end, and
    without it the chain takes more nodes. On the gateway family it never
    raises the bound: the search stops counting it after
    ``SearchOptions.together`` estimates (bound.py, ``Together``)."""
    _, on_chain = _run(chain(8), 1)
    _, without = _run(chain(8), 1, together=0)
    _, on_gateway = _run(gateway(4, 4), 1)
    chain_together = _together(on_chain)
    assert chain_together.raised and chain_together.counted
    assert _together(without).counted is False
    assert on_chain.stats.nodes < without.stats.nodes
    gateway_together = _together(on_gateway)
    assert not gateway_together.raised and not gateway_together.counted
    assert gateway_together.left == 0


@pytest.mark.parametrize(
    "texts",
    [chain(8), gateway(4, 4), fusion(4, 3, 4, 3)],
    ids=["chain", "gateway", "fusion"],
)
def test_counting_the_together_least_cost_or_not_changes_nothing_found(
    texts: tuple[str, str],
) -> None:
    """The ten cheapest, the together least cost never counted and always
    counted, are the same configurations at the same costs (an admissible
    bound the more or the less changes only the work)."""
    never, _ = _run(texts, 10, together=0)
    always, _ = _run(texts, 10, together=10**9)
    usual, _ = _run(texts, 10)
    assert [cost for cost, _ in never] == [cost for cost, _ in always] == [c for c, _ in usual]
    last = usual[-1][0]  # ties at the last cost may be cut differently
    for other in (never, always):
        assert sorted(c for c in usual if c[0] < last) == sorted(c for c in other if c[0] < last)
