"""``cfgplan plan DOMAIN STATE``: ranked admissible configurations (thesis 4.5).

The formats are :mod:`cfgplan.cli.formats`; several goals plan sequences of
configurations (:mod:`cfgplan.cli.sequence`); ``--fallbacks`` adds the
robustness report (:mod:`cfgplan.cli.fallbacks`).
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NamedTuple, NoReturn

import typer

from cfgplan.cli import formats
from cfgplan.cli.app import EXIT_NONE, say, usage_error, write_output
from cfgplan.cli.options import (
    DomainArg,
    ForceOpt,
    GoalsOpt,
    StateArg,
    WeightsOpt,
    choice_of,
    completing,
    count_of,
    errors_as_json,
    load_problem,
    no_rank,
    number_of,
    rank_option,
)
from cfgplan.cli.registry import command
from cfgplan.configuration.model import Configuration
from cfgplan.files import check_target
from cfgplan.notation import call_text
from cfgplan.planner import Run, Stats
from cfgplan.planner.options import RACE, SearchOptions
from cfgplan.problem import Problem

if TYPE_CHECKING:  # the reconfiguration is loaded only for --fallbacks (start-up)
    from cfgplan.reconfigure.fallbacks import Fallback

# Loaded only when needed (start-up): cfgplan.cli.sequence for several
# goals, cfgplan.cli.fallbacks for --fallbacks, cfgplan.planner.explain when
# nothing is found, cfgplan.configuration.describe for --format json.

FORMATS = ("table", "lisp", "json", "jsonl")
ENGINES = ("both", "search", "solver")
K = 10
"""How many configurations ``plan`` lists without ``-k``."""


class _Asked(NamedTuple):
    """What to print, once the configurations are found (a named tuple: a
    frozen dataclass takes about four times as long to define)."""

    format: str
    details: bool
    first: int  # the rank of the first configuration shown
    listing: bool  # -k or --all (not --rank): the table says when more exist
    output: Path | None
    force: bool

    @property
    def stream(self) -> bool:
        """Print each configuration as soon as it is proven: a listing (not
        ``--rank``, which shows one only once those before it are found) in
        jsonl or lisp, on stdout. The one place this is decided: what
        :func:`_plan` printed, :func:`_print` does not print again."""
        return self.listing and self.output is None and self.format in ("jsonl", "lisp")


def _progress(stats: Stats, elapsed: float) -> None:
    say(f"planning... {elapsed:.1f} s, {stats.nodes:,} nodes, {stats.derivations:,} derivations")


def _plan(
    problem: Problem,
    limit: int | None,
    distinct: bool,
    time_limit: float | None,
    asked: _Asked,
    options: SearchOptions,
) -> tuple[Run, list[Configuration], bool | None]:
    """Plan (streaming what is proven when asked to); with ``-k N`` the search
    looks ahead for one more, within as much work again, to say whether more
    exist (:attr:`~cfgplan.planner.plan.Run.ahead`): the run, the
    configurations, and that (None: not known)."""
    search = Run(  # the time limit counts from here: planning, not reading
        problem.task,
        problem.goal_call,
        limit,
        distinct,
        time_limit,
        _progress,
        # The solver finds the first configuration and looks no further.
        ahead=limit is not None and asked.listing and not options.solver,
        options=options,
    )
    configs: list[Configuration] = []
    for config in search:
        configs.append(config)
        if asked.stream:  # printed as soon as it is proven
            sys.stdout.write(formats.streamed(problem, config, len(configs), asked.format))
            sys.stdout.flush()
    return search, configs, search.status.more


def _nothing(
    problem: Problem, search: Run, format_: str, output: Path | None, force: bool
) -> NoReturn:
    """No admissible configuration: why, on stderr; with JSON, also as data on
    stdout (scripts never get an empty answer); exit 3."""
    from cfgplan.configuration.describe import to_json
    from cfgplan.planner.explain import explain, explanation

    say("\n".join(explain(search.report, call_text(problem.goal_call))))
    explained = explanation(search.report)
    if format_ == "json":
        extra = {"explanation": explained}
        text = to_json(problem.goal_call, [], problem.state.media, formats.stats(search), extra)
        write_output(text, output, force)
    elif format_ == "jsonl":
        summary = formats.summary(problem, [], search, explained=explained)
        write_output(summary, output, force)
    raise typer.Exit(EXIT_NONE)


def _print(
    problem: Problem,
    configs: list[Configuration],
    search: Run,
    more: bool | None,
    backups: "list[Fallback] | None",
    asked: _Asked,
) -> None:
    """The configurations (and fallbacks) in the format asked for: on stdout,
    the same bytes as in the ``-o`` file (what was streamed is not repeated)."""
    first = asked.first
    if backups is not None:
        from cfgplan.cli.fallbacks import fallback_lisp, fallback_table
    if asked.format == "jsonl":
        summary = formats.summary(problem, configs, search, more)
        if asked.stream:
            sys.stdout.write(summary)  # every line before it went out as it was found
            return
        text = formats.jsonl(problem, configs, search, more, first)
    elif asked.format == "json":
        from cfgplan.configuration.describe import to_json

        extra = None if backups is None else {"fallbacks": [fb.record() for fb in backups]}
        stats = formats.stats(search, more)
        text = to_json(problem.goal_call, configs, problem.state.media, stats, extra, first)
    elif asked.stream:
        if backups is not None:
            sys.stdout.write(fallback_lisp(configs[0], backups, first))
        return  # every description went out as it was found
    elif asked.format == "lisp":
        text = formats.lisp(problem, configs, first)
        if backups is not None:
            text += fallback_lisp(configs[0], backups, first)
    else:
        # Where the solver ran (alone or racing), no second was looked for: nothing to say.
        noted = more if asked.listing and not search.raced else False
        text = formats.table(problem, configs, asked.details, noted, first)
        if backups is not None:
            text += fallback_table(configs[0], backups, first)
    write_output(text, asked.output, asked.force)


@command(short_help="Plan ranked admissible configurations (4.5), or sequences of them.")
def plan(
    domain: DomainArg,
    state: StateArg,
    goal: GoalsOpt = None,
    k: Annotated[
        int | None,
        typer.Option(
            "-k",
            metavar="N",
            parser=count_of(1),
            help=f"How many configurations, cheapest first (default {K}).",
        ),
    ] = None,
    all_: Annotated[
        bool, typer.Option("--all", help="Every configuration (instead of -k).")
    ] = False,
    rank: Annotated[
        int | None,
        rank_option("Only the configuration of rank N, 1 being the cheapest (instead of -k)."),
    ] = None,
    derivations: Annotated[
        bool,
        typer.Option(
            "--derivations",
            help="List every derivation, as the thesis counts them, "
            "instead of distinct configurations.",
        ),
    ] = False,
    weights: WeightsOpt = None,
    format_: Annotated[
        str,
        typer.Option(
            "--format",
            metavar="|".join(FORMATS),
            parser=choice_of(FORMATS, "a format"),
            autocompletion=completing(FORMATS),
            help="Output format (default table).",
            show_default=False,
        ),
    ] = "table",
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
            "--time-limit",
            metavar="S",
            parser=number_of(0),
            help="Stop after S seconds of planning with what was found.",
        ),
    ] = None,
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", metavar="FILE", help="Write here, not stdout."),
    ] = None,
    force: ForceOpt = False,
    switch: Annotated[
        float,
        typer.Option(
            "--switch",
            metavar="W",
            parser=number_of(0),
            help="Sequences: the weight of each functionality or channel started or "
            "stopped between two steps (default 0).",
            show_default=False,
        ),
    ] = 0.0,
    engine: Annotated[
        str,
        typer.Option(
            "--engine",
            metavar="|".join(ENGINES),
            parser=choice_of(ENGINES, "an engine"),
            autocompletion=completing(ENGINES),
            help="How -k 1 finds the cheapest: both (the default: the search, and where it "
            "has not ended after a moment the solver beside it in a second process; the "
            "first to end answers, with the same configuration), search (best first, alone) "
            "or solver (clingo proves the cheapest cost, then a walk in the thesis's order "
            "finds the same configuration as the search; where the cost is not proven within "
            "the time limit, the search goes on).",
            show_default=False,
        ),
    ] = "both",
    fallbacks: Annotated[
        bool,
        typer.Option(
            "--fallbacks",
            help="For each resource of the configuration shown first (functionality, robot, "
            "medium), the best configuration if it fails, or none: the single points of "
            "failure (--time-limit bounds each one's search).",
        ),
    ] = False,
) -> None:
    """Plan ranked admissible configurations for a goal (thesis 4.5), or
    sequences of them for several goals in order.

    Exit codes: 0 found, 1 invalid input, 2 usage, 3 no admissible configuration
    (or none of the --rank asked for). With --format json or jsonl, an input
    error is also printed on stdout, as one JSON object.
    """
    if rank is not None and (k is not None or all_):
        usage_error("shows one configuration; -k and --all list several: give one", "--rank")
    if all_ and k is not None:
        usage_error("lists that many; --all lists every one: give one", "-k")
    if engine == "solver" and (all_ or (k or K) != 1 or (rank or 1) != 1):
        usage_error("finds the cheapest configuration only: it goes with -k 1", "--engine")
    with errors_as_json(format_):  # input errors on stdout too, as JSON
        if output is not None:
            check_target(output, force)  # before planning, which may take long
        problem = load_problem(domain, state, goal, weights, sequence=True)
        limit = rank if rank is not None else (None if all_ else (k or K))
        if len(problem.goals) > 1:
            if engine == "solver":
                usage_error("plans one goal: a sequence is planned by the search", "--engine")
            from cfgplan.cli.sequence import SequenceOptions, plan_sequences

            options = SequenceOptions(limit, switch, time_limit, verbose, details, rank)
            write_output(plan_sequences(problem, options, format_), output, force)
            return
        # The solver's one configuration is no listing: the table says nothing of more.
        listing = rank is None and engine != "solver"
        asked = _Asked(format_, details, rank or 1, listing, output, force)
        engine_options = SearchOptions(
            solver=engine == "solver", race=RACE if engine == "both" else None
        )
        search, configs, more = _plan(
            problem, limit, not derivations, time_limit, asked, engine_options
        )
        if verbose:
            _verbose(search)
        if search.status.stopped:
            found = f"{len(configs)} configuration(s)" if configs else "nothing"
            say(f"cfgplan: search stopped ({search.status.value}); reporting {found} found so far")
        if not configs:
            _nothing(problem, search, format_, output, force)
        if rank is not None:
            if len(configs) < rank:
                no_rank(call_text(problem.goal_call), len(configs), rank)
            configs = configs[rank - 1 :]
        backups = _fallbacks(problem, configs[0], time_limit) if fallbacks else None
        _print(problem, configs, search, more, backups, asked)


def _fallbacks(
    problem: Problem, config: Configuration, time_limit: float | None
) -> "list[Fallback]":
    """The fallbacks of ``config``; ``--time-limit`` bounds each one's search."""
    from cfgplan.reconfigure.fallbacks import fallbacks as fallbacks_of

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
