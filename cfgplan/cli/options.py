"""The arguments and options the commands share, and what they read.

``DOMAIN`` and ``STATE`` are read, checked and compiled by :func:`load_problem`
(thesis 4.4); ``--goal`` (one, or several for a sequence), ``--weights``
(the cost of 4.5) and ``--rank`` (which configuration, :func:`choose`) mean
the same in every command. Values are parsed here, with cfgplan's own
wording for a bad one (``-k: 'abc' is not a whole number``), never the
wording of the libraries underneath.
"""

from __future__ import annotations

import gc
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer

from cfgplan.cli.app import EXIT_NONE, ONE_COMMAND, remember_source, report, say, usage_error
from cfgplan.configuration.cost import Weights, parse_weights
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError, Diagnostic
from cfgplan.notation import call_text
from cfgplan.option_values import choice, number, whole
from cfgplan.problem import GOAL_SOURCE, Problem, load
from cfgplan.syntax.reader import collection_paused

if TYPE_CHECKING:
    from cfgplan.planner.report import Report
    from cfgplan.runtime.faults import Injection
    from cfgplan.runtime.options import Option

YOUNG = 50_000
"""New objects between two young collections of the cycle collector in a
process that plans and exits (Python's default: 700). A search makes many
objects that live on (nodes, the bounds' caches) and next to no cyclic
garbage (none on the benchmark families): fewer, larger young collections
walk fewer of them before they die or grow old. Planning chain D=200 took
475 ms instead of 550. A command that runs on (:func:`load_problem`'s
``lasting``) keeps Python's pace: its pauses stay short."""

__all__ = [
    "DomainArg",
    "ForceOpt",
    "GoalOpt",
    "GoalsOpt",
    "RankOpt",
    "StateArg",
    "WeightsOpt",
    "choice_of",
    "choose",
    "completing",
    "count_of",
    "errors_as_json",
    "injections",
    "load_problem",
    "no_rank",
    "number_of",
    "parsed",
    "print_errors",
    "rank_option",
]


def parsed(parse: Callable[[str], Any]) -> Callable[[str], Any]:
    """``parse`` as a typer parser: its ``ValueError`` (or a
    :class:`CfgplanError`) becomes a usage error with its own message."""

    def convert(text: str) -> Any:
        try:
            return parse(text)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        except CfgplanError as exc:
            raise typer.BadParameter(str(exc)) from None

    return convert


def option(spec: Option[Any]) -> Any:
    """The typer option of one of the run options of :mod:`cfgplan.runtime.options`
    (the emitted programs build theirs from the same)."""
    parse = None if spec.parse is None else parsed(spec.parse)
    return typer.Option(
        spec.flag, metavar=spec.metavar, help=spec.help, parser=parse, show_default=False
    )


def count_of(low: int) -> Callable[[str], int]:
    """Whole numbers of at least ``low``, for typer."""
    return parsed(whole(low))


def number_of(low: float, *, above: bool = False) -> Callable[[str], float]:
    """Finite numbers of at least (``above``: more than) ``low``, for typer."""
    return parsed(number(low, above=above))


def choice_of(values: tuple[str, ...], what: str) -> Callable[[str], str]:
    """One of ``values``, for typer: ``'yaml' is not a format: choose table, ...``."""
    return parsed(choice(values, what))


def completing(values: tuple[str, ...]) -> Callable[[str], list[str]]:
    """Shell completion of an option that takes one of ``values``."""
    return lambda incomplete: [v for v in values if v.startswith(incomplete)]


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
        metavar="GOAL",
        help="Goal method instance, e.g. '(do-cross-door Pippi Door1)'; "
        "default: the state file's (goal ...).",
    ),
]
GoalsOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--goal",
        metavar="GOAL",
        help="Goal method instance, e.g. '(do-cross-door Pippi Door1)'; give it several "
        "times for a sequence of configurations, one goal after the other. "
        "Default: the state file's (goal ...) or (sequence ...).",
    ),
]
WeightsOpt = Annotated[
    Weights | None,
    typer.Option(
        "--weights",
        metavar="NAME=W,...",
        parser=parsed(parse_weights),
        help="Cost weights, e.g. robot=10,global=3,local=1,functionality=1,device=10 "
        "(the thesis's, and the default). A functionality's :cost replaces its weight.",
    ),
]


def rank_option(help_text: str) -> Any:
    """The ``--rank N`` option (1 the cheapest), with its command's help."""
    return typer.Option(
        "--rank", metavar="N", parser=count_of(1), help=help_text, show_default=False
    )


RankOpt = Annotated[int, rank_option("Which configuration, 1 being the cheapest (default 1).")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Overwrite the -o file.")]


def load_problem(
    domain: Path,
    state: Path,
    goal: str | list[str] | None,
    weights: Weights | None,
    sequence: bool = False,
    lasting: bool = False,
) -> Problem:
    """Read, check and compile; warnings go to stderr. Unless ``sequence``,
    the command plans one configuration and refuses a sequence of goals.
    ``lasting``: the command runs on after planning (a society), so the cycle
    collector keeps Python's pace (see :data:`YOUNG`)."""
    goals = [goal] if isinstance(goal, str) else list(goal or [])
    if goals:
        remember_source(GOAL_SOURCE, "\n".join(f"(goal {g})" for g in goals))
    if ONE_COMMAND.get():
        # What was read (and every module imported) lives as long as the
        # process: out of the cycle collector's sight, a search that makes
        # many nodes is not slowed by collections walking it again and again
        # (13 % of planning chain D=200). Frozen objects are never collected,
        # so only where one command is the whole process. Frozen before the
        # collector is back on: else its first young collection walks all
        # that was read (the collector was off, all of it is young), some
        # 300,000 objects for chain D=200, 25 ms.
        with collection_paused():
            problem = load(domain, state, goals, weights)
            gc.freeze()
        if not lasting:
            gc.set_threshold(YOUNG, *gc.get_threshold()[1:])
    else:
        problem = load(domain, state, goals, weights)
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


_AS_JSON: ContextVar[bool] = ContextVar("errors_as_json", default=False)
"""Whether the command prints its errors on stdout as JSON (:func:`errors_as_json`)."""


def injections(texts: Sequence[str] | None, problem: Problem) -> tuple[Injection, ...]:
    """The ``--inject`` faults, each aimed at a robot or device of the state
    and, for an instance, at a functionality of the domain with its arguments
    (:func:`cfgplan.runtime.faults.misaimed`); else a usage error (exit 2) with
    a "did you mean", as a typo would make the fault a silent no-op."""
    from cfgplan.runtime.faults import misaimed, parse_injection

    out = []
    for text in texts or ():
        injection = parse_injection(text)
        wrong = misaimed(injection, problem.task.agents, problem.task.functionalities)
        if wrong is not None:
            usage_error(wrong.message + (f" ({wrong.hint})" if wrong.hint else ""), "--inject")
        out.append(injection)
    return tuple(out)


def print_errors(diagnostics: Sequence[Diagnostic]) -> None:
    """Errors refusing the input, as the command prints them on stdout: one
    JSON :class:`~cfgplan.cli.errors.ErrorDocument` under
    :func:`errors_as_json`, else nothing (stderr has them, always)."""
    if _AS_JSON.get() and any(d.is_error for d in diagnostics):
        from cfgplan.cli.errors import ErrorDocument, dump  # pydantic: on this path only

        sys.stdout.write(dump(ErrorDocument.of(diagnostics)))


@contextmanager
def errors_as_json(format_: str) -> Iterator[None]:
    """With ``--format json`` or ``jsonl``, an input error refusing the
    command (a :class:`CfgplanError`: unreadable file, parse or check error,
    bad goal, an output it may not overwrite) is also printed on stdout as
    JSON, so that a tool reads it; :func:`~cfgplan.cli.app.main` still
    prints it on stderr and exits 1."""
    token = _AS_JSON.set(format_ in ("json", "jsonl"))
    try:
        yield
    except CfgplanError as exc:
        print_errors(exc.diagnostics)
        raise
    finally:
        _AS_JSON.reset(token)


def no_rank(what: str, found: int, rank: int, kind: str = "configuration") -> NoReturn:
    """``--rank`` past the last one: the same words in every command; exit 3."""
    refusal = [
        Diagnostic(
            "error",
            f"{what} has {found} {kind}{'' if found == 1 else 's'}, none of rank {rank}",
            hint=f"--rank 1 to {found}",
        )
    ]
    report(refusal)
    print_errors(refusal)
    raise typer.Exit(EXIT_NONE)


def nothing(report_: Report, goal: str) -> NoReturn:
    """No admissible configuration: why, on stderr; exit 3."""
    from cfgplan.planner.explain import explain  # only when nothing is found

    say("\n".join(explain(report_, goal)))
    raise typer.Exit(EXIT_NONE)


def choose(problem: Problem, rank: int) -> Configuration:
    """The configuration of ``rank`` (1: the cheapest); exit 3 when there are fewer."""
    from cfgplan.planner import plan  # here: a robot that follows plans nothing (run)

    configs, search = plan(problem.task, problem.goal_call, limit=rank)
    goal = call_text(problem.goal_call)
    if not configs:
        nothing(search.report, goal)
    if len(configs) < rank:
        no_rank(goal, len(configs), rank)
    return configs[rank - 1]
