"""``cfgplan plan`` for several goals: ranked sequences of configurations.

The search is :class:`cfgplan.planner.sequence.SequenceSearch`. Outputs: the
table lists sequences with their steps; ``--format lisp`` prints each step's
configuration description (4.4) under a step header, then the state changes
it makes; JSON holds ``{"sequences": [{"rank", "total_cost", "steps":
[{"goal", "state_changes", "configuration"}]}], "communication_checked",
"stats"}`` (:mod:`cfgplan.configuration.schema`); ``jsonl`` one sequence a line.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from itertools import islice
from typing import TYPE_CHECKING, Any

import typer

from cfgplan.cli.app import EXIT_NONE, say
from cfgplan.cli.formats import NO_MEDIA, more_note, plain
from cfgplan.cli.options import no_rank
from cfgplan.configuration.cost import fmt
from cfgplan.configuration.describe import to_dict, to_text
from cfgplan.configuration.model import Configuration
from cfgplan.notation import call_text
from cfgplan.problem import Problem

if TYPE_CHECKING:  # loaded by the two functions that search (start-up)
    from cfgplan.planner.sequence import PlannedSequence, SequenceSearch


@dataclass(frozen=True)
class SequenceOptions:
    limit: int | None  # None: every sequence
    switch: float
    time_limit: float | None
    verbose: bool
    details: bool
    rank: int | None = None  # only the sequence of this rank


def plan_sequences(problem: Problem, options: SequenceOptions, format_: str) -> str:
    """Plan, report on stderr, and return the text to print (exit 3 when none)."""
    from cfgplan.planner.sequence import SequenceSearch

    # -k N looks for one sequence more than it lists, with bounded work, to say
    # whether more exist (as for one goal: cfgplan.planner.search)
    ahead = options.limit is not None and options.rank is None
    search = SequenceSearch(
        problem.goal_calls,
        problem.task,
        options.switch,
        options.time_limit,
        limit=options.limit,
        ahead=ahead,
    )
    found = list(search)
    more = search.status.more
    if search.status.stopped:
        say(f"cfgplan: search stopped ({search.status.value}); reporting {len(found)} found")
    if not found:
        _impossible(problem, search)
        raise typer.Exit(EXIT_NONE)
    first = options.rank or 1
    if options.rank is not None:
        if len(found) < options.rank:
            no_rank(_goals(problem), len(found), options.rank, "sequence")
        found = found[options.rank - 1 :]
    if format_ == "json":
        document = _document(problem, found, search, first, more)
        return json.dumps(document, indent=2, ensure_ascii=False) + "\n"
    if format_ == "jsonl":
        return "".join(
            json.dumps(_sequence(s, rank, problem), ensure_ascii=False) + "\n"
            for rank, s in enumerate(found, first)
        )
    if format_ == "lisp":
        return _lisp(problem, found, first)
    return (
        _table(problem, found, options.details, first)
        + (more_note(len(found), "sequence", more) if more or more is None else "")
        + ("" if problem.state.media else f"note: {NO_MEDIA}\n")
    )


def _goals(problem: Problem) -> str:
    """``do-cross-door(Pippi, Door1) then do-cross-door(Emil, Door1)``."""
    return " then ".join(call_text(g) for g in problem.goal_calls)


def first_step(problem: Problem, rank: int) -> Configuration:
    """The first step's configuration of the sequence of ``rank`` (1: the
    cheapest): what ``cfgplan run`` starts with; exit 3 when there are fewer."""
    from cfgplan.planner.sequence import SequenceSearch

    search = SequenceSearch(problem.goal_calls, problem.task)
    found = list(islice(search, rank))
    if not found:
        _impossible(problem, search)
        raise typer.Exit(EXIT_NONE)
    if len(found) < rank:
        no_rank(_goals(problem), len(found), rank, "sequence")
    return found[rank - 1].steps[0].configuration


def _impossible(problem: Problem, search: SequenceSearch) -> None:
    """Say which step has no admissible configuration, and why."""
    from cfgplan.planner.explain import explain  # only when nothing is found

    blocked = search.blocked()
    if blocked is None:
        say("no admissible sequence found")
        return
    step, _, report = blocked
    goal = call_text(problem.goal_calls[step])
    where = (
        "in the initial state"
        if step == 0
        else ("in any state the steps before it reach; in the state the cheapest of them leaves")
    )
    say(f"no admissible sequence: step {step + 1}, {goal}, has no configuration {where}:")
    say("\n".join(explain(report, goal)))


def _sequence(planned: PlannedSequence, rank: int, problem: Problem) -> dict[str, Any]:
    return {
        "rank": rank,
        "total_cost": _number(planned.total),
        "steps": [
            {
                "goal": call_text(step.goal),
                "state_changes": list(step.changes),
                "configuration": to_dict(step.configuration, 1, problem.state.media),
            }
            for step in planned.steps
        ],
    }


def _document(
    problem: Problem,
    found: list[PlannedSequence],
    search: SequenceSearch,
    first: int,
    more: bool | None,
) -> dict[str, Any]:
    return {
        "goals": [call_text(g) for g in problem.goal_calls],
        "sequences": [_sequence(s, rank, problem) for rank, s in enumerate(found, first)],
        "communication_checked": bool(problem.state.media),
        "stats": {
            "more": more,
            "exhausted": search.status.exhausted,
            "stopped": search.status.value if search.status.stopped else None,
        },
    }


def _number(x: float) -> int | float:
    return int(x) if float(x).is_integer() else x


def _lisp(problem: Problem, found: list[PlannedSequence], first: int) -> str:
    goals = ", ".join(call_text(g) for g in problem.goal_calls)
    parts = [f";; cfgplan: {len(found)} sequence(s) for {goals}"]
    if not problem.state.media:
        parts.append(f";; {NO_MEDIA}")
    for rank, planned in enumerate(found, first):
        parts.append(f";; sequence {rank}, total cost {fmt(planned.total)}")
        for i, step in enumerate(planned.steps, 1):
            parts.append(f";; step {i}: {call_text(step.goal)}")
            parts.append(to_text(step.configuration, problem.state.media))
            parts += [f";; then {change}" for change in step.changes]
    return "\n".join(parts) + "\n"


def _table(problem: Problem, found: list[PlannedSequence], details: bool, first: int) -> str:
    from rich.table import Table  # loaded for tables only (start-up)

    table = Table(title=f"Sequences for {_goals(problem)}")
    table.add_column("rank", justify="right")
    table.add_column("total", justify="right")
    table.add_column("step", justify="right")
    table.add_column("goal")
    table.add_column("cost", justify="right")
    table.add_column("robots")
    table.add_column("then the state changes")
    if details:
        table.add_column("functionality instances")
    for rank, planned in enumerate(found, first):
        for i, step in enumerate(planned.steps, 1):
            config = step.configuration
            row = [
                str(rank) if i == 1 else "",
                fmt(planned.total) if i == 1 else "",
                str(i),
                call_text(step.goal),
                fmt(config.cost),
                ", ".join(config.agents),
                "\n".join(step.changes),
            ]
            if details:
                row.append("\n".join(str(f) for f in config.functionalities))
            table.add_row(*row, end_section=i == len(planned.steps))
    return plain(table, 200 if details else 120)
