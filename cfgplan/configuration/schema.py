"""The JSON that ``cfgplan plan --format json`` and ``--format jsonl`` print, as models.

The outputs themselves are built from dicts where they are printed
(:func:`cfgplan.configuration.describe.to_json`, :mod:`cfgplan.cli.formats`,
:mod:`cfgplan.cli.sequence`, :meth:`cfgplan.reconfigure.fallbacks.Fallback.record`,
:func:`cfgplan.planner.explain.explanation`); these models describe them for
the documentation (their JSON Schema is the reference page "JSON output") and
for the tests, which validate the real outputs of every bundled domain against
them: every model forbids keys it does not name, so neither can drift from the
other. Nothing on the command's path imports this module.

A configuration is the thesis's configuration description (4.4), with the
media of 4.6 and the reliability of 7.2.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from cfgplan.documents import Closed, Number
from cfgplan.planner.report import Condition

Stopped = Literal["time limit", "interrupted"]
"""The values of :class:`cfgplan.planner.report.Status` that stop a run."""

__all__ = [
    "ChannelEntry",
    "ConfigurationEntry",
    "DeadEnd",
    "Explanation",
    "FallbackEntry",
    "FunctionalityEntry",
    "MediumEntry",
    "PlanDocument",
    "PlanSummary",
    "Rejection",
    "SearchStats",
    "SequenceDocument",
    "SequenceEntry",
    "SequenceStats",
    "StepEntry",
]


class FunctionalityEntry(Closed):
    """A functionality instance of the configuration (4.4)."""

    id: str = Field(description="Its label in the configuration, e.g. `F3`.")
    name: str = Field(description="The functionality, e.g. `cross-door`.")
    args: list[str] = Field(description="Its arguments, the robot first.")
    robot: str = Field(description="The agent (robot or device) it runs on.")


class ChannelEntry(Closed):
    """A channel between two functionality instances (4.4)."""

    kind: Literal["local", "global"] = Field(
        description="`local` (one robot) or `global` (between two); an `(any ...)` channel "
        "appears as what it became."
    )
    from_: str = Field(alias="from", description="The id of the functionality that writes.")
    to: str = Field(description="The id of the functionality that reads.")
    from_robot: str = Field(description="The agent of `from`.")
    to_robot: str = Field(description="The agent of `to`.")
    data: list[str] = Field(description="The data descriptor, e.g. `[pos, Pippi, Door1]`.")
    bandwidth: Number | None = Field(description="The bandwidth declared for the data, or null.")
    medium: int | None = Field(
        description="Index into `media` of the medium carrying it; null for local channels, "
        "channels between ends on one robot, or when the state declares no media (4.6)."
    )


class ConfigurationEntry(Closed):
    """One admissible configuration, ranked; a line of ``--format jsonl``."""

    rank: int = Field(description="1 for the cheapest (ties in a fixed order).")
    cost: Number = Field(
        description="`10·robots + 3·global + local + functionalities` under `--weights`."
    )
    robots: list[str] = Field(description="The robots used, in the order of the functionalities.")
    devices: list[str] = Field(description="The `(device X)` agents used, apart from the robots.")
    reliability: float = Field(
        description="Product of the functionalities' reliabilities and, for each global "
        "channel, of the most reliable medium between its robots (1.0 when none is declared)."
    )
    derivation: int = Field(
        description="With `--derivations`, which derivation it is (1-based, in the thesis's "
        "order); otherwise how many derivations the search had completed when it found it."
    )
    proven: bool = Field(
        description="False when the search was stopped before it could prove this one the "
        "cheapest of its rank."
    )
    functionalities: list[FunctionalityEntry]
    channels: list[ChannelEntry]
    postconditions: list[str] = Field(description="Each an atom or `(not ATOM)`.")
    media_loads: list[Number] | None = Field(
        default=None,
        description="The bandwidth each medium of `media` carries, in its order; "
        "left out when the state declares no media.",
    )


class MediumEntry(Closed):
    """A medium of the state (4.6)."""

    type: str
    from_: str = Field(alias="from")
    to: str
    capacity: Number
    reliability: Number | None


class SearchStats(Closed):
    """How the search went: the work of the engine that answered. Where the
    solver raced the search (`-k 1`, `--engine both`, once the search had not
    ended after a moment), which one answered first may differ from run to run;
    the configurations do not."""

    more: bool | None = Field(
        description="True when `-k` cut the list and more configurations exist; null when "
        "that is not known (the search for one more stopped at its work limit: as much "
        "work again as the listed ones took; or the solver ran, alone or racing the "
        "search: it finds the first and does not look for a second)."
    )
    engine: Literal["search", "solver"] = Field(
        description="Which engine found the configurations: the best-first search, or the "
        "solver (`--engine solver`, or the solver's process that raced the search and ended "
        "first)."
    )
    nodes: int = Field(description="Partial configurations created.")
    expansions: int = Field(description="Nodes expanded.")
    derivations: int = Field(description="Complete derivations reached.")
    duplicates: int = Field(description="Partial configurations reached again and skipped.")
    rejected: int = Field(description="Complete ones refused by an admissibility check.")
    exhausted: bool = Field(description="True when the search ran to its end.")
    stopped: Stopped | None = Field(description="Why the search was stopped, or null.")


class DeadEnd(Closed):
    """A branch of the search that ended, and why."""

    where: str = Field(description="The method version.")
    condition: Condition
    reason: str
    source: str | None = Field(description="`file:line:col` in the domain, or null.")
    failed: str | None = Field(description="The precondition that failed, or null.")
    bindings: dict[str, str] = Field(description="Variable -> value when it failed.")


class Rejection(Closed):
    """Complete configurations refused for one reason."""

    condition: Condition
    reason: str
    configurations: int = Field(description="How many were rejected so.")


class Explanation(Closed):
    """Why nothing is admissible, as ``plan`` prints it on stderr."""

    dead_ends: list[DeadEnd]
    rejected: list[Rejection]
    complete: bool = Field(
        description="False when the search was stopped before it could see every dead end."
    )


class FallbackConfiguration(Closed):
    """A fallback's configuration: a :class:`ConfigurationEntry` without ``rank``."""

    cost: Number
    robots: list[str]
    devices: list[str]
    reliability: float
    derivation: int
    proven: bool
    functionalities: list[FunctionalityEntry]
    channels: list[ChannelEntry]
    postconditions: list[str]
    media_loads: list[Number] | None = None


class FallbackEntry(Closed):
    """``--fallbacks``: what to run if one resource of the first configuration fails."""

    resource: str = Field(description="`compass(Emil)`, a robot, or a medium.")
    kind: Literal["functionality", "robot", "medium"]
    withdrawn: list[str] = Field(description="The facts its failure takes from the state.")
    cost: Number | None = Field(description="The fallback's cost, or null: none is admissible.")
    robots: list[str] | None
    stopped: list[str] = Field(description="Functionality instances the switch stops.")
    started: list[str] = Field(description="Functionality instances the switch starts.")
    configuration: FallbackConfiguration | None
    why: list[str] | None = Field(description="When there is no fallback: the explanation.")
    proven: bool


class PlanDocument(Closed):
    """``cfgplan plan --format json`` for one goal: one document, also when
    nothing is admissible (exit 3; then ``explanation`` says why)."""

    goal: str = Field(description="The goal method instance, e.g. `do-cross-door(Pippi, Door1)`.")
    configurations: list[ConfigurationEntry] = Field(description="Ranked, cheapest first.")
    communication_checked: bool = Field(description="False when the state declares no media.")
    media: list[MediumEntry] | None = Field(
        default=None, description="The state's media; left out when it declares none."
    )
    stats: SearchStats
    fallbacks: list[FallbackEntry] | None = Field(default=None, description="With `--fallbacks`.")
    explanation: Explanation | None = Field(
        default=None, description="Only when `configurations` is empty."
    )


class PlanSummary(Closed):
    """The last line of ``cfgplan plan --format jsonl`` (one goal)."""

    goal: str
    count: int = Field(description="How many configurations were printed.")
    communication_checked: bool
    stats: SearchStats
    explanation: Explanation | None = Field(
        default=None, description="Only when there was no configuration."
    )


class StepEntry(Closed):
    """One step of a sequence: its goal, the state changes it makes, its configuration."""

    goal: str
    state_changes: list[str]
    configuration: ConfigurationEntry = Field(description="Its `rank` is always 1.")


class SequenceEntry(Closed):
    """A sequence of configurations (several goals); a line of ``--format jsonl``."""

    rank: int
    total_cost: Number
    steps: list[StepEntry]


class SequenceStats(Closed):
    """How the sequence search went."""

    more: bool = Field(description="True when `-k` cut the list and more sequences exist.")
    exhausted: bool
    stopped: Stopped | None


class SequenceDocument(Closed):
    """``cfgplan plan --format json`` for several goals (``(sequence ...)`` or
    ``--goal`` given more than once)."""

    goals: list[str]
    sequences: list[SequenceEntry]
    communication_checked: bool
    stats: SequenceStats
