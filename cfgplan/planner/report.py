"""Dead ends: why a branch of the search ended, kept for the user.

Every step of the planner that cannot go on returns a :class:`DeadEnd` naming
the admissibility condition (3.5) or planner rule (4.5) it broke; the search
collects them in a :class:`Report` (first occurrence kept, in the order met),
which :mod:`cfgplan.planner.explain` turns into "why nothing was found".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import NamedTuple

from cfgplan.ir.model import Span


class Condition(Enum):
    """What a dead end broke; the value is the word shown to the user."""

    PRECONDITION = "precondition"  # causal admissibility: no binding satisfies them
    BINDING = "unbound variable"  # a name does not match, a variable bound by nothing
    INFORMATION = "information admissibility"  # an input not fed, data not produced
    LOCATION = "channel location"  # a local/global channel's ends on the wrong robots
    CYCLE = "cycle"  # the channels form a cycle (the sort of 5.1 fails)
    RECURSION = "recursion"  # a method instance recurs on its own expansion path
    DOMAIN = "domain"  # a call that is neither a method nor a functionality
    COMMUNICATION = "communication admissibility"  # the media cannot carry the channels


class StopReason(Enum):
    """Why a search ended before it had listed everything it was asked for."""

    TIME_LIMIT = "time limit"
    INTERRUPTED = "interrupted"


class Engine(Enum):
    """Which engine found a run's configurations: the best-first search, or
    the solver (:mod:`cfgplan.planner.solver`, :mod:`cfgplan.planner.portfolio`)."""

    SEARCH = "search"
    SOLVER = "solver"


class DeadEnd(NamedTuple):
    """Why a branch ended: ``where`` it happened, the ``reason``, the source
    ``span`` when it points into the domain, and the condition broken."""

    where: str
    reason: str
    span: Span | None = None
    condition: Condition = Condition.PRECONDITION
    failed: str = ""  # the precondition no binding got past, as written
    bindings: tuple[tuple[str, str], ...] = ()  # the bindings it failed under

    def describe(self) -> str:
        return f"{self.where}: {self.reason}" if self.where else self.reason


@dataclass
class Report:
    """Dead ends met during expansion (first occurrence of each place and
    condition kept, in the order met) and configurations rejected once
    complete (4.5 step 4), in the order rejected."""

    dead: dict[tuple[str, Condition], DeadEnd] = field(default_factory=dict)
    rejected: list[DeadEnd] = field(default_factory=list)
    unfinished: bool = False  # the search that collected them was stopped
    undecided: bool = False
    """The search itself was stopped before it found a configuration or
    proved there is none: the dead ends are only those met so far."""

    def note(self, dead: DeadEnd) -> None:
        self.dead.setdefault((dead.where, dead.condition), dead)

    def reject(self, dead: DeadEnd) -> None:
        self.rejected.append(dead)


@dataclass
class Stats:
    """What the search did: shown by ``--verbose`` and in JSON output."""

    nodes: int = 0  # nodes taken to be expanded or finished
    expansions: int = 0  # method instances expanded
    replays: int = 0  # of them, sub-derivations done again in one step (replay.py)
    derivations: int = 0  # complete derivations met (duplicates included)
    duplicates: int = 0  # complete derivations whose configuration was listed already
    rejected: int = 0  # complete derivations found inadmissible (4.5 step 4)
    pruned: int = 0  # nodes the bounds proved to have no completion
    seconds: float = 0.0
    complete: bool = True  # False when a limit stopped the search early
