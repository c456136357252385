"""What each part of a configuration costs (thesis 3.5, 7.2): every pricing
rule of the planner, in one place.

A configuration costs ``10·robots + 3·global + local + functionalities``
with the thesis's weights (:class:`cfgplan.configuration.cost.Weights`): an
agent's weight (a robot's, or a device's for an agent the state declares
``(device X)``), each channel's weight by its kind, each functionality's
``:cost`` or the functionality weight; with ``reliability=W``, ``W·(−ln p)``
more for each functionality of reliability p and for each global channel
between two robots, p that of the most reliable medium between them. The
search adds these up as it places functionalities and channels
(:mod:`cfgplan.planner.partial`, :mod:`cfgplan.planner.wiring`), the bounds
add up the least of them a node must still pay (:mod:`cfgplan.planner.bound`,
:mod:`cfgplan.planner.summary`, :mod:`cfgplan.planner.graph`), the solver
writes them into its program (:mod:`cfgplan.planner.solver`), and the unit
costs are ranked by is the greatest common divisor of them all
(:meth:`Costs.levels`). Each reads them here: changing what something costs
is a change to this module. (The independent admissibility checker,
:mod:`cfgplan.configuration.admissible`, keeps its own copy on purpose: it
checks the planner's answers.)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

from cfgplan.configuration.cost import Weights
from cfgplan.planner.levels import Levels, unit_of


class Declared(Protocol):
    """What is read of a functionality schema
    (:class:`cfgplan.planner.task.FunctionalitySchema`)."""

    @property
    def cost(self) -> float | None: ...
    @property
    def reliability(self) -> float | None: ...


@dataclass(frozen=True, eq=False, repr=False)
class Costs:
    """The prices of one task's parts (:attr:`cfgplan.planner.task.Task.costs`)."""

    weights: Weights
    devices: frozenset[str]
    """Agents the state declares ``(device X)``: weighted as devices, not robots."""
    links: Mapping[tuple[str, str], float]
    """(sender, receiver) -> the most reliable medium's reliability (1 if unsaid)."""
    reliability: Mapping[tuple[str, ...], float]
    """Reliabilities of functionality instances that replace their schema's."""
    declared: tuple[float, ...]
    """Every functionality schema's ``:cost`` (those that have one)."""

    def functionality(self, schema: Declared, call: tuple[str, ...]) -> float:
        """The functionality's ``:cost``, else the functionality weight (3.5),
        plus ``W·(−ln p)`` for its reliability p when ``reliability=W``."""
        cost = schema.cost if schema.cost is not None else self.weights.functionality
        if self.weights.reliability:
            cost += self.weights.reliability * -math.log(self.reliability_of(schema, call))
        return cost

    def reliability_of(self, schema: Declared, call: tuple[str, ...]) -> float:
        """A functionality instance's reliability (7.2): the state's for the
        instance, else its schema's, else 1."""
        found = self.reliability.get(call)
        if found is not None:
            return found
        return schema.reliability if schema.reliability is not None else 1.0

    def channel(self, kind: str) -> float:
        """A channel's weight by its kind (3.5); :meth:`link` adds its media's."""
        return self.weights.global_ if kind == "global" else self.weights.local

    def link(self, sender: str, receiver: str) -> float:
        """``W·(−ln p)`` for a global channel between two robots: p is the most
        reliable medium from ``sender`` to ``receiver`` (1 when none says)."""
        if not self.weights.reliability or sender == receiver:
            return 0.0
        return self.weights.reliability * -math.log(self.links.get((sender, receiver), 1.0))

    def agent(self, agent: str) -> float:
        """What running something on ``agent`` costs: a robot's or a device's weight."""
        return self.weights.device if agent in self.devices else self.weights.robot

    def levels(self, *more: float) -> Levels:
        """How costs are ranked (:mod:`cfgplan.planner.levels`): by the unit
        every price above is a multiple of (and ``more``, e.g. a sequence's
        switch weight), unless reliability adds logarithms to them."""
        w = self.weights
        if w.reliability:
            return Levels(None)
        return Levels(
            unit_of([w.robot, w.device, w.global_, w.local, w.functionality, *more, *self.declared])
        )
