"""Scalable domain families for the benchmarks (thesis 7.2-7.3: many robots).

Each generator returns the text of a domain and of a state with its goal,
for ``python -m benchmarks.run`` and the tests:

- ``wall(K, N, L)``, ``relay(D, W, V)``: the shapes the search was first tuned on;
- ``ecology(N, R, C)``, ``media_tight(N, R, C)``, ``fusion(M, V, P, H)``,
  ``chain(D)``, ``delegation(N)``, ``gateway(N, D)``: structures it was not
 : covering with shared robots and devices, tight media, weighted
  covering with ``:cost``, long plateaus of equal cost, recursion, media that
  let each camera serve one robot;
- ``dag(D)``, ``conversion(D)``: shared and recursive sub-derivations, one
  ground method instance under many ancestors;
- ``deliveries(S, R)``: a sequence of S configurations;
- :mod:`benchmarks.families.weak`: structures the search is still weak on
  (docs/explanation/planner.md, "Weak spots"), not in the benchmark table.
"""

from benchmarks.families.chain import chain
from benchmarks.families.delegation import delegation
from benchmarks.families.ecology import ecology, media_tight
from benchmarks.families.fusion import fusion
from benchmarks.families.gateway import gateway
from benchmarks.families.relay import relay
from benchmarks.families.shared import conversion, dag
from benchmarks.families.steps import deliveries
from benchmarks.families.wall import wall

__all__ = [
    "chain",
    "conversion",
    "dag",
    "delegation",
    "deliveries",
    "ecology",
    "fusion",
    "gateway",
    "media_tight",
    "relay",
    "wall",
]
