"""The partitioned bound priced from another node's evaluation
(cfgplan.planner.partition.Least.again) is the bound priced from scratch, float
for float: every node a real search refines, its bound and its split (the
price of each expansion of its top item), with the evaluations reused as
much as can be and not at all."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from benchmarks.families import chain, ecology, fusion, gateway, media_tight, wall
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.partition import Least, Partition, Split
from cfgplan.planner.plan import plan
from tests.planner.test_scale import problem_of

Refined = tuple[Partition, Partial, frozenset[str]]


def refined_nodes(texts: tuple[str, str], limit: int) -> list[Refined]:
    """The nodes the stronger bound priced in a search for the ``limit``
    cheapest (from the first node on), in the order it priced them, with
    the agents certain at each."""
    problem = problem_of(texts)
    seen: list[Refined] = []
    original = Partition.split

    def recording(
        self: Partition, node: Partial, certain: frozenset[str], apart: bool = True
    ) -> tuple[float | None, Split | None]:
        seen.append((self, node, certain))
        return original(self, node, certain, apart)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Partition, "split", recording)
        plan(problem.task, problem.goal_call, limit=limit, options=SearchOptions(warm=0))
    return seen


def priced(
    nodes: list[Refined],
    reuse: float,
    smallest: int,
    cold: bool,
    made: list[Partition] | None = None,
) -> Iterator[tuple[float | None, Split | None]]:
    """Each node's bound and split by a new partition of its own task (those
    made go to ``made``): every node priced from scratch (``cold``), or each
    from the last one with its pending items whenever ``reuse`` and
    ``smallest`` (:class:`cfgplan.planner.partition.Least`) allow."""
    partitions: dict[int, Partition] = {}
    for searched, node, certain in nodes:
        found = partitions.get(id(searched))
        if found is None:
            found = partitions[id(searched)] = Partition(searched.grounder)
            found.least.reuse = reuse
            found.least.smallest = smallest
            if made is not None:
                made.append(found)
        if cold:
            found.occurrences.forget()
        yield found.split(node, certain)


FAMILIES = [
    (fusion(4, 3, 4, 3), "fusion-4"),
    (fusion(8, 3, 6, 6), "fusion-8"),
    (ecology(18, 3, 3), "ecology-18"),
    (media_tight(8, 3, 2), "media-tight-8"),
    (gateway(4, 4), "gateway-4"),
    (chain(8), "chain-8"),
    (wall(3, 4, 3), "wall-3"),
]


@pytest.mark.parametrize("texts", [f[0] for f in FAMILIES], ids=[f[1] for f in FAMILIES])
def test_a_bound_priced_from_another_nodes_is_the_bound_priced_from_scratch(
    texts: tuple[str, str],
) -> None:
    """Every node a search for the 10 cheapest refines: bound, rest and each
    expansion's price exactly equal (==, not approximately) whether priced
    from scratch, from the last node with the same pending items whenever
    possible (``reuse`` unbounded, ``smallest`` 0), or by the default rules; and where
    siblings share pending items, every node but the first three of each
    stack was priced from another's (the test is not vacuous)."""
    nodes = refined_nodes(texts, 10)
    assert nodes
    scratch = list(priced(nodes, 0.0, 0, cold=True))
    partitions: list[Partition] = []
    always = list(priced(nodes, float("inf"), 0, cold=False, made=partitions))
    usual = list(priced(nodes, Least.reuse, Least.smallest, cold=False))
    for (bound, split), (bound2, split2), (bound3, split3) in zip(
        scratch, always, usual, strict=True
    ):
        assert bound == bound2 == bound3
        assert split == split2 == split3
    stacks = {tuple(item.call for item in node.stack) for _, node, _ in nodes}
    if len(stacks) * 3 < len(nodes):  # each stack: twice from scratch, once recorded
        assert sum(p.least.reused for p in partitions) >= len(nodes) - 3 * len(stacks)
