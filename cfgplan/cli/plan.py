"""``cfgplan plan DOMAIN STATE``: ranked admissible configurations (thesis 4.5)."""

from __future__ import annotations

import io
import json
import shutil
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, NoReturn

import typer
from rich.console import Console
from rich.table import Table

from cfgplan.cli.app import EXIT_NONE, app, remember_source, report, say, write_output
from cfgplan.cli.fallbacks import fallback_lisp, fallback_table
from cfgplan.cli.sequence import SequenceOptions, plan_sequences
from cfgplan.configuration.cost import Weights, fmt, parse_weights
from cfgplan.configuration.describe import channel_text, to_dict, to_json, to_text
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError, Diagnostic, printable
from cfgplan.files import check_target
from cfgplan.notation import call_text
from cfgplan.planner import Run, Stats
from cfgplan.planner.explain import explain, explanation
from cfgplan.problem import GOAL_SOURCE, Problem, load
from cfgplan.reconfigure.fallbacks import Fallback
from cfgplan.reconfigure.fallbacks import fallbacks as fallbacks_of


class Format(StrEnum):
    table = "table"
    lisp = "lisp"
    json = "json"
    jsonl = "jsonl"


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
GoalsOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--goal",
        help="Goal method instance, e.g. '(do-cross-door Pippi Door1)'; give it several "
        "times for a sequence of configurations, one goal after the other. "
        "Default: the state file's (goal ...) or (sequence ...).",
    ),
]
WeightsOpt = Annotated[
    str | None,
    typer.Option(
        "--weights",
        help="Cost weights, e.g. robot=10,global=3,local=1,functionality=1,device=10 "
        "(the thesis's, and the default). A functionality's :cost replaces its weight.",
    ),
]


def load_problem(
    domain: Path,
    state: Path,
    goal: str | list[str] | None,
    weights: str | None,
    sequence: bool = False,
) -> Problem:
    """Read, check and compile; warnings go to stderr. Unless ``sequence``,
    the command plans one configuration and refuses a sequence of goals."""
    goals = [goal] if isinstance(goal, str) else list(goal or [])
    if goals:
        remember_source(GOAL_SOURCE, "\n".join(f"(goal {g})" for g in goals))
    problem = load(domain, state, goals, weights_option(weights))
    report(problem.warnings)
    if len(problem.goals) > 1 and not sequence:
        raise CfgplanError(
            [
                Diagnostic(
                    "error",
                    f"{state} holds a sequence of {len(problem.goals)} goals; "
                    "this command plans one configuration",
                    hint="choose one with --goal; cfgplan plan plans the whole sequence",
                )
            ]
        )
    return problem


def _progress(stats: Stats, elapsed: float) -> None:
    say(f"planning... {elapsed:.1f} s, {stats.nodes:,} nodes, {stats.derivations:,} derivations")


def _stats(search: Run, more: bool = False) -> dict[str, object]:
    s = search.stats
    return {
        "more": more,
        "nodes": s.nodes,
        "expansions": s.expansions,
        "derivations": s.derivations,
        "duplicates": s.duplicates,
        "rejected": s.rejected,
        "exhausted": s.complete,
        "stopped": search.stopped.value if search.stopped else None,
    }


def _table(problem: Problem, configs: list[Configuration], details: bool, more: bool) -> str:
    """The table for people: names with control characters escaped (a name
    holding ESC cannot drive the terminal)."""
    table = Table(title=printable(f"Configurations for {call_text(problem.goal_call)}"))
    table.add_column("rank", justify="right")
    table.add_column("cost", justify="right")
    table.add_column("robots")
    devices = any(c.devices for c in configs)
    if devices:
        table.add_column("devices")
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
            *([", ".join(c.devices)] if devices else []),
            str(len(c.functionalities)),
            str(c.local_channels),
            str(c.global_channels),
        ]
        if details:
            row.append("\n".join(str(f) for f in c.functionalities))
            row.append("\n".join(channel_text(ch) for ch in c.channels))
        table.add_row(*(printable(cell, keep="\n") for cell in row))
    buffer = io.StringIO()
    # With --details the table is as wide as the terminal (200 when not one).
    width = shutil.get_terminal_size((200, 24)).columns if details else 100
    Console(file=buffer, width=width, force_terminal=False, color_system=None).print(table)
    if more:
        wider = len(configs) + 10
        buffer.write(f"note: more configurations exist: --all lists them all, -k {wider} more\n")
    if not problem.state.media:
        buffer.write("note: the state declares no media: communication admissibility not checked\n")
    if any(not c.proven for c in configs):
        buffer.write("* not proven optimal: the search was stopped before it could prove it\n")
    return buffer.getvalue()


def _streamed(problem: Problem, config: Configuration, rank: int, format_: Format) -> str:
    """One configuration as ``--format jsonl`` or ``lisp`` prints it, alone."""
    if format_ is Format.jsonl:
        line = to_dict(config, rank, problem.state.media)
        return json.dumps(line, ensure_ascii=False) + "\n"
    head = ""
    if rank == 1:
        head = f";; cfgplan: configurations for {call_text(problem.goal_call)}\n"
        if not problem.state.media:
            head += ";; the state declares no media: communication admissibility not checked\n"
    shown = f";; rank {rank}" + ("" if config.proven else ", not proven optimal")
    return head + shown + "\n" + to_text(config, problem.state.media) + "\n"


def _summary(
    problem: Problem,
    configs: list[Configuration],
    search: Run,
    more: bool = False,
    explained: dict[str, object] | None = None,
) -> str:
    """The last line of ``--format jsonl``: what was planned for, and how."""
    doc: dict[str, object] = {
        "goal": call_text(problem.goal_call),
        "count": len(configs),
        "communication_checked": bool(problem.state.media),
        "stats": _stats(search, more),
    }
    if explained is not None:
        doc["explanation"] = explained
    return json.dumps(doc, ensure_ascii=False) + "\n"


def _plan(
    problem: Problem,
    limit: int | None,
    distinct: bool,
    time_limit: float | None,
    stream: bool,
    format_: Format,
) -> tuple[Run, list[Configuration], bool]:
    """Plan (streaming what is proven when asked to); with ``-k N`` one more is
    planned, to say whether more exist: the run, the configurations, and that."""
    search = Run(  # the time limit counts from here: planning, not reading
        problem.task,
        problem.goal_call,
        None if limit is None else limit + 1,
        distinct,
        time_limit,
        _progress,
    )
    configs: list[Configuration] = []
    for config in search:
        if limit is not None and len(configs) == limit:
            return search, configs, True
        configs.append(config)
        if stream:  # printed as soon as it is proven
            sys.stdout.write(_streamed(problem, config, len(configs), format_))
            sys.stdout.flush()
    return search, configs, False


def _nothing(
    problem: Problem, search: Run, format_: Format, output: Path | None, force: bool
) -> NoReturn:
    """No admissible configuration: why, on stderr; with JSON, also as data on
    stdout (scripts never get an empty answer); exit 3."""
    say("\n".join(explain(search.report, call_text(problem.goal_call))))
    explained = explanation(search.report)
    if format_ is Format.json:
        extra = {"explanation": explained}
        text = to_json(problem.goal_call, [], problem.state.media, _stats(search), extra)
        write_output(text, output, force)
    elif format_ is Format.jsonl:
        write_output(_summary(problem, [], search, explained=explained), output, force)
    raise typer.Exit(EXIT_NONE)


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
    goal: GoalsOpt = None,
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
    switch: Annotated[
        float,
        typer.Option(
            "--switch",
            min=0,
            help="Sequences: the weight of each functionality or channel started or "
            "stopped between two steps (default 0).",
        ),
    ] = 0.0,
    fallbacks: Annotated[
        bool,
        typer.Option(
            "--fallbacks",
            help="For each resource of the cheapest configuration (functionality, robot, "
            "medium), the best configuration if it fails, or none: the single points of "
            "failure (--time-limit bounds each one's search).",
        ),
    ] = False,
) -> None:
    """Plan ranked admissible configurations for a goal (thesis 4.5), or
    sequences of them for several goals in order.

    Exit codes: 0 found, 1 invalid input, 2 usage, 3 no admissible configuration.
    """
    if output is not None:
        check_target(output, force)  # before planning, which may take long
    problem = load_problem(domain, state, goal, weights, sequence=True)
    if len(problem.goals) > 1:
        options = SequenceOptions(None if all_ else k, switch, time_limit, verbose, details)
        text = plan_sequences(problem, options, format_.value)
        write_output(text, output, force)
        return
    limit = None if all_ else k
    stream = output is None and format_ in (Format.jsonl, Format.lisp)
    search, configs, more = _plan(problem, limit, not derivations, time_limit, stream, format_)
    if verbose:
        _verbose(search)
    if search.stopped:
        found = f"{len(configs)} configuration(s)" if configs else "nothing"
        say(f"cfgplan: search stopped ({search.stopped.value}); reporting {found} found so far")
    if not configs:
        _nothing(problem, search, format_, output, force)
    backups = _fallbacks(problem, configs[0], time_limit) if fallbacks else None
    if format_ is Format.jsonl:
        summary = _summary(problem, configs, search, more)
        if stream:
            sys.stdout.write(summary)
            return
        text = "".join(_streamed(problem, c, i, format_) for i, c in enumerate(configs, 1))
        text += summary
    elif format_ is Format.json:
        extra = None if backups is None else {"fallbacks": [fb.record() for fb in backups]}
        stats = _stats(search, more)
        text = to_json(problem.goal_call, configs, problem.state.media, stats, extra)
    elif stream:
        if backups is not None:
            sys.stdout.write(fallback_lisp(configs[0], backups))
        return  # every description went out as it was found
    elif format_ is Format.lisp:
        text = _lisp(problem, configs)
        if backups is not None:
            text += fallback_lisp(configs[0], backups)
    else:
        text = _table(problem, configs, details, more)
        if backups is not None:
            text += fallback_table(configs[0], backups)
    write_output(text, output, force)


def _fallbacks(
    problem: Problem, config: Configuration, time_limit: float | None
) -> list[Fallback]:
    """The fallbacks of ``config``; ``--time-limit`` bounds each one's search."""
    return fallbacks_of(problem.task, problem.goal_call, config, time_limit=time_limit)


def _verbose(search: Run) -> None:
    s = search.stats
    say(
        f"search: {s.nodes} nodes, {s.expansions} method expansions, {s.derivations} derivations, "
        f"{s.duplicates} duplicates, {s.rejected} rejected, {s.seconds * 1000:.1f} ms"
    )
    for dead in search.report.dead.values():
        where = f" ({dead.span})" if dead.span is not None else ""
        say(f"  dead end: {dead.where}{where}: {dead.condition.value}: {dead.reason}")
    for dead in search.report.rejected:
        say(f"  rejected: {dead.condition.value}: {dead.describe()}")
