"""``cfgplan render DOMAIN STATE -o FILE``: a configuration or a method hierarchy
as a picture (Fig. 4.3, 6.4, 6.8, 6.11 style; ``--hierarchy``: Fig. 4.4 style).

The format comes from the suffix of ``-o``: ``.dot`` (DOT source, always
available), ``.svg`` or ``.png`` (laid out by :mod:`cfgplan.backends.render`).
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

from pathlib import Path
from typing import Annotated, Literal

import typer

from cfgplan.backends.dot import configuration_dot
from cfgplan.backends.dot_hierarchy import hierarchy_dot
from cfgplan.backends.render import render as render_dot
from cfgplan.cli.app import EXIT_INPUT, report, usage_error
from cfgplan.cli.options import (
    DomainArg,
    ForceOpt,
    GoalOpt,
    StateArg,
    WeightsOpt,
    choose,
    load_problem,
    rank_option,
)
from cfgplan.cli.registry import command
from cfgplan.configuration.cost import fmt
from cfgplan.diagnostics import CfgplanError
from cfgplan.files import check_target, write_file
from cfgplan.notation import call_text
from cfgplan.problem import Problem

Kind = Literal["dot", "svg", "png"]
SUFFIXES: dict[str, Kind] = {".dot": "dot", ".svg": "svg", ".png": "png"}


def output_format(output: Path) -> Kind:
    """``dot``, ``svg`` or ``png`` from the file name; anything else is a usage error."""
    kind = SUFFIXES.get(output.suffix.lower())
    if kind is None:
        raise typer.BadParameter(
            f"cannot tell the format of {output.name!r}: "
            f"the file name must end in {', '.join(SUFFIXES)}",
            param_hint="'-o' / '--output'",
        )
    return kind


def write_bytes(data: bytes, output: Path, force: bool) -> None:
    """Write ``data`` to ``output`` in one step, refusing to overwrite it without
    --force and to write through a link (:func:`cfgplan.files.write_file`)."""
    write_file(output, data, force)


def configuration_source(problem: Problem, rank: int) -> str:
    """DOT of the configuration of the given rank; exit 3 when there is none."""
    config = choose(problem, rank)
    title = f"{call_text(problem.goal_call)}: rank {rank}, cost {fmt(config.cost)}"
    return configuration_dot(config, title=title, first=problem.goal_call[1:])


@command(short_help="Draw a configuration (Fig. 4.3) or a method hierarchy (Fig. 4.4).")
def render(
    domain: DomainArg,
    state: StateArg,
    output: Annotated[
        Path,
        typer.Option(
            "-o",
            "--output",
            metavar="FILE",
            help="File to write; its suffix gives the format: .dot, .svg, .png.",
        ),
    ],
    goal: GoalOpt = None,
    rank: Annotated[
        int | None,
        rank_option("Which configuration, 1 being the cheapest (default 1; not with --hierarchy)."),
    ] = None,
    weights: WeightsOpt = None,
    hierarchy: Annotated[
        bool,
        typer.Option(
            "--hierarchy",
            help="Draw the goal's hierarchy of methods and functionalities (Fig. 4.4) "
            "instead of a configuration.",
        ),
    ] = False,
    force: ForceOpt = False,
) -> None:
    """Draw a configuration (Fig. 4.3) or a method hierarchy (Fig. 4.4).

    Exit codes: 0 written, 1 invalid input or existing file, 2 usage,
    3 no admissible configuration (or none of that rank).
    """
    if hierarchy and rank is not None:
        usage_error("picks a configuration; --hierarchy draws the methods: give one", "--rank")
    kind = output_format(output)
    try:
        check_target(output, force)
        problem = load_problem(domain, state, goal, weights)
        if hierarchy:
            source = hierarchy_dot(problem.task, problem.goal_call)
        else:
            source = configuration_source(problem, rank or 1)
        data = source.encode("utf-8") if kind == "dot" else render_dot(source, kind)
        write_bytes(data, output, force)
    except CfgplanError as exc:
        report(exc.diagnostics)
        raise typer.Exit(EXIT_INPUT) from None
