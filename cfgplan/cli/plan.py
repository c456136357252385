"""``cfgplan plan DOMAIN STATE``: ranked admissible configurations (thesis 4.5)."""

from __future__ import annotations

import io
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from cfgplan.cli.app import EXIT_NONE, app, remember_source, report, say, write_output
from cfgplan.configuration.cost import Weights, fmt, parse_weights
from cfgplan.configuration.describe import call_text, channel_text, to_json, to_text
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError, printable
from cfgplan.files import check_target
from cfgplan.planner.explain import explain
from cfgplan.planner.search import Search, Stats
from cfgplan.planner.search import plan as run_plan
from cfgplan.problem import GOAL_SOURCE, Problem, load


class Format(StrEnum):
    table = "table"
    lisp = "lisp"
    json = "json"


def weights_option(text: str | None) -> Weights | None:
    if text is None:
        return None
    try:
        return parse_weights(text)
    except CfgplanError as exc:
        raise typer.BadParameter(str(exc)) from None


DomainArg = Annotated[
    Path,
    typer.Argument(
        metavar="DOMAIN", help="Domain file: make-functionality and make-config-method forms."
    ),
]
StateArg = Annotated[
    Path,
    typer.Argument(metavar="STATE", help="State file: facts, media and an optional (goal ...)."),
]
GoalOpt = Annotated[
    str | None,
    typer.Option(
        "--goal",
        help="Goal method instance, e.g. '(do-cross-door Pippi Door1)'; "
        "default: the state file's (goal ...).",
    ),
]
WeightsOpt = Annotated[
    str | None,
    typer.Option(
        "--weights",
        help="Cost weights, e.g. robot=10,global=3,local=1,functionality=1 "
        "(the thesis's, and the default). A functionality's :cost replaces its weight.",
    ),
]


def load_problem(domain: Path, state: Path, goal: str | None, weights: str | None) -> Problem:
    """Read, check and compile; warnings go to stderr."""
    if goal is not None:
        remember_source(GOAL_SOURCE, f"(goal {goal})")
    problem = load(domain, state, goal, weights_option(weights))
    report(problem.warnings)
    return problem


def _progress(stats: Stats, elapsed: float) -> None:
    say(f"planning... {elapsed:.1f} s, {stats.nodes:,} nodes, {stats.derivations:,} derivations")


def _stats(search: Search) -> dict[str, object]:
    s = search.stats
    return {
        "nodes": s.nodes,
        "expansions": s.expansions,
        "derivations": s.derivations,
        "duplicates": s.duplicates,
        "rejected": s.rejected,
        "exhausted": s.complete,
        "stopped": search.stopped or None,
    }


def _table(problem: Problem, configs: list[Configuration], details: bool) -> str:
    """The table for people: names with control characters escaped (a name
    holding ESC cannot drive the terminal)."""
    table = Table(title=printable(f"Configurations for {call_text(problem.goal_call)}"))
    table.add_column("rank", justify="right")
    table.add_column("cost", justify="right")
    table.add_column("robots")
    table.add_column("functionalities", justify="right")
    table.add_column("local", justify="right")
    table.add_column("global", justify="right")
    if details:
        table.add_column("functionality instances")
        table.add_column("channels")
    for rank, c in enumerate(configs, 1):
        row = [
            str(rank),
            fmt(c.cost) + ("" if c.proven else " *"),
            ", ".join(c.robots),
            str(len(c.functionalities)),
            str(c.local_channels),
            str(c.global_channels),
        ]
        if details:
            row.append("\n".join(str(f) for f in c.functionalities))
            row.append("\n".join(channel_text(ch) for ch in c.channels))
        table.add_row(*(printable(cell, keep="\n") for cell in row))
    buffer = io.StringIO()
    Console(
        file=buffer, width=200 if details else 100, force_terminal=False, color_system=None
    ).print(table)
    if not problem.state.media:
        buffer.write("note: the state declares no media: communication admissibility not checked\n")
    if any(not c.proven for c in configs):
        buffer.write("* not proven optimal: the search was stopped before it could prove it\n")
    return buffer.getvalue()


def _lisp(problem: Problem, configs: list[Configuration]) -> str:
    parts = [f";; cfgplan: {len(configs)} configuration(s) for {call_text(problem.goal_call)}"]
    if not problem.state.media:
        parts.append(";; the state declares no media: communication admissibility not checked")
    for rank, c in enumerate(configs, 1):
        parts.append(f";; rank {rank}" + ("" if c.proven else ", not proven optimal"))
        parts.append(to_text(c, problem.state.media))
    return "\n".join(parts) + "\n"


@app.command()
def plan(
    domain: DomainArg,
    state: StateArg,
    goal: GoalOpt = None,
    k: Annotated[
        int, typer.Option("-k", min=1, help="How many configurations, cheapest first.")
    ] = 10,
    all_: Annotated[
        bool, typer.Option("--all", help="Every configuration (overrides -k).")
    ] = False,
    derivations: Annotated[
        bool,
        typer.Option(
            "--derivations",
            help="List every derivation, as the thesis counts them, "
            "instead of distinct configurations.",
        ),
    ] = False,
    weights: WeightsOpt = None,
    format_: Annotated[Format, typer.Option("--format", help="Output format.")] = Format.table,
    details: Annotated[
        bool, typer.Option("--details", help="table: add the functionalities and channels.")
    ] = False,
    verbose: Annotated[
        bool,
        typer.Option("--verbose", "-v", help="Search statistics and every dead end, on stderr."),
    ] = False,
    time_limit: Annotated[
        float | None,
        typer.Option(
            "--time-limit", min=0, help="Stop after this many seconds with what was found."
        ),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Write here, not stdout.")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite the -o file.")] = False,
) -> None:
    """Plan ranked admissible configurations for a goal (thesis 4.5).

    Exit codes: 0 found, 1 invalid input, 2 usage, 3 no admissible configuration.
    """
    if output is not None:
        check_target(output, force)  # before planning, which may take long
    problem = load_problem(domain, state, goal, weights)
    configs, search = run_plan(
        problem.task,
        problem.goal_call,
        limit=None if all_ else k,
        distinct=not derivations,
        time_limit=time_limit,
        progress=_progress,
    )
    if verbose:
        _verbose(search)
    if search.stopped:
        found = f"{len(configs)} configuration(s)" if configs else "nothing"
        say(f"cfgplan: search stopped ({search.stopped}); reporting {found} found so far")
    if not configs:
        say("\n".join(explain(search.report, call_text(problem.goal_call))))
        raise typer.Exit(EXIT_NONE)
    if format_ is Format.json:
        text = to_json(problem.goal_call, configs, bool(problem.state.media), _stats(search))
    elif format_ is Format.lisp:
        text = _lisp(problem, configs)
    else:
        text = _table(problem, configs, details)
    write_output(text, output, force)


def _verbose(search: Search) -> None:
    s = search.stats
    say(
        f"search: {s.nodes} nodes, {s.expansions} method expansions, {s.derivations} derivations, "
        f"{s.duplicates} duplicates, {s.rejected} rejected, {s.seconds * 1000:.1f} ms"
    )
    for dead in search.report.dead.values():
        where = f" ({dead.span})" if dead.span is not None else ""
        say(f"  dead end: {dead.where}{where}: {dead.condition}: {dead.reason}")
    for condition, reason in search.report.rejected:
        say(f"  rejected: {condition}: {reason}")
