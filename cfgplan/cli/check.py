"""``cfgplan check DOMAIN [STATE]``: read and check, report every problem."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from cfgplan.check import check as run_checks
from cfgplan.cli.app import EXIT_INPUT, app, report
from cfgplan.cli.options import DomainArg
from cfgplan.diagnostics import printable
from cfgplan.syntax.reader import read_domain, read_state


@app.command(short_help="Check a domain (and a state with its goal) without planning.")
def check(
    domain: DomainArg,
    state: Annotated[
        Path | None,
        typer.Argument(metavar="STATE", help="State file: facts, media, optional (goal ...)."),
    ] = None,
) -> None:
    """Check a domain (and a state with its goal) without planning.

    Prints every error and warning as file:line:col with the source line;
    exits 1 when there is an error (warnings alone do not fail).
    """
    parsed, _ = read_domain(domain)
    world = None
    if state is not None:
        world, _ = read_state(state)
    diagnostics = run_checks(parsed, world, world.goal if world else None)
    report(diagnostics)
    errors = sum(1 for d in diagnostics if d.is_error)
    warnings = len(diagnostics) - errors
    if errors:
        typer.echo(f"{errors} error(s), {warnings} warning(s)", err=True)
        raise typer.Exit(EXIT_INPUT)
    versions = len(parsed.methods)
    methods = len({m.name.signature for m in parsed.methods})
    summary = (
        f"ok: {domain}: {len(parsed.functionalities)} functionalities, "
        f"{methods} methods ({versions} versions)"
    )
    if world is not None:
        summary += f"; {state}: {len(world.facts)} facts, {len(world.media)} media"
        if world.goal is not None:
            summary += f", goal {world.goal.call}"
    if warnings:
        summary += f"; {warnings} warning(s)"
    typer.echo(printable(summary))
