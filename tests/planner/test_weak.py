"""The structures the search is still weak on (benchmarks/families/weak.py and
structured.py, docs/explanation/planner.md, "Weak spots") are slow at size,
never wrong: at sizes the depth-first oracle can list, the ten cheapest
derivations, best first with both bounds on every node, are the oracle's
first ten."""

from __future__ import annotations

import pytest

from benchmarks.families import structured, weak
from cfgplan.configuration.cost import Weights
from tests.planner.oracle import depth_first
from tests.planner.problems import FIRST_NODE, load_text, run


@pytest.mark.parametrize(
    "texts",
    [
        weak.overlap(4),
        weak.overlap(5, 4),
        weak.mutual(4),
        weak.triangulate(7),
        weak.pairs(8),
        structured(1, pieces=2, versions=2, kinds=3, robots=2, depth=1, density=0.6),
        structured(2, pieces=2, versions=2, kinds=3, robots=2, depth=2, density=0.6, media=True),
    ],
    ids=[
        "overlap-4",
        "overlap-5-4",
        "mutual-4",
        "triangulate-7",
        "pairs-8",
        "structured-1",
        "structured-2-media",
    ],
)
def test_the_ten_cheapest_are_the_oracles(texts: tuple[str, str]) -> None:
    problem = load_text(*texts)
    oracle = depth_first(problem, Weights())
    assert len(oracle) >= 10  # enough to rank
    found = run(problem, limit=10, distinct=False, options=FIRST_NODE)
    assert [(c.cost, c.identity()) for c in found] == oracle[:10]
    assert [(c.cost, c.identity()) for c in run(problem, limit=10, distinct=False)] == oracle[:10]
