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


class Status(Enum):
    """How a run ended: the one status a search, a sequence search, the
    command line, the JSON output (``exhausted``, ``more``, ``stopped``) and
    the explanation of "nothing found" read. The value is the word shown to
    the user."""

    COMPLETE = "complete"
    """The search ran to its end: everything there is was listed."""
    MORE = "more"
    """The list was cut at ``-k N`` and at least one more exists (the look-ahead
    of :mod:`cfgplan.planner.search` found it)."""
    CUT = "cut"
    """The list was cut at ``-k N`` and no more was looked for (``--rank``)."""
    UNKNOWN = "unknown"
    """The list was cut and whether more exist is not known: the look-ahead's
    work ran out, or the solver answered (it finds the first and looks no further)."""
    TIME_LIMIT = "time limit"
    """Stopped by the time limit: what was listed is what was found by then."""
    INTERRUPTED = "interrupted"
    """Stopped by the user (Ctrl-C)."""

    @property
    def stopped(self) -> bool:
        """The search was stopped before it could say what it was asked."""
        return self in (Status.TIME_LIMIT, Status.INTERRUPTED)

    @property
    def exhausted(self) -> bool:
        """The search ran to its end (JSON ``exhausted``)."""
        return self is Status.COMPLETE

    @property
    def more(self) -> bool | None:
        """Whether more than the listed exist (JSON ``more``): True, one was
        found; None, not known; False, none, or none was looked for."""
        return True if self is Status.MORE else None if self is Status.UNKNOWN else False


class Engine(Enum):
    """Which engine found a run's configurations: the best-first search, or
    the solver (:mod:`cfgplan.planner.solver`, :mod:`cfgplan.planner.solver`)."""

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
    status: Status = Status.COMPLETE
    """How the search that met them ended: stopped, they are only those met
    so far (JSON ``complete`` is false)."""
    explaining: bool = False
    """They were met by the search run again without its bounds, after the
    run had proved that nothing is admissible (:meth:`Run._explain
    <cfgplan.planner.plan.Run._explain>`): stopped, the answer stands and
    only the list of dead ends may be short. Otherwise a stopped search has
    decided nothing: one may exist."""

    @property
    def undecided(self) -> bool:
        """The run was stopped before it found a configuration or proved there is none."""
        return self.status.stopped and not self.explaining

    def note(self, dead: DeadEnd) -> None:
        self.dead.setdefault((dead.where, dead.condition), dead)

    def reject(self, dead: DeadEnd) -> None:
        self.rejected.append(dead)


@dataclass
class Stats:
    """What the search did: shown by ``--verbose`` and in JSON output."""

    nodes: int = 0  # nodes taken to be expanded or finished
    expansions: int = 0  # method instances expanded
    replays: int = 0  # of them, sub-derivations done again in one step (grow.py)
    derivations: int = 0  # complete derivations met (duplicates included)
    duplicates: int = 0  # complete derivations whose configuration was listed already
    rejected: int = 0  # complete derivations found inadmissible (4.5 step 4)
    pruned: int = 0  # nodes the bounds proved to have no completion
    seconds: float = 0.0
