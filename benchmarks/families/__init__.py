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
- ``deliveries(S, R)``: a sequence of S configurations; ``missions(G, H)``: a
  sequence of G independent goals over H helpers;
- ``any_delegation(N)``: delegation from any robot to any other, dead ends
  found at a chain's last step;
- ``structured(seed, ...)``: randomised fusion over shared, deep filter
  hierarchies, with media whose capacity binds;
- :mod:`benchmarks.families.weak`: structures the search is still weak on
  (docs/explanation/planner.md, "Weak spots"), not in the benchmark table.
"""

from benchmarks.families.chain import chain
from benchmarks.families.delegation import any_delegation, delegation
from benchmarks.families.ecology import ecology, media_tight
from benchmarks.families.fusion import fusion
from benchmarks.families.gateway import gateway
from benchmarks.families.relay import relay
from benchmarks.families.shared import conversion, dag
from benchmarks.families.steps import deliveries, missions
from benchmarks.families.structured import structured
from benchmarks.families.wall import wall

__all__ = [
    "any_delegation",
    "chain",
    "conversion",
    "dag",
    "delegation",
    "deliveries",
    "ecology",
    "fusion",
    "gateway",
    "media_tight",
    "missions",
    "relay",
    "structured",
    "wall",
]
