"""``cfgplan check DOMAIN [STATE]``: read and check, report every problem
(thesis 4.4); ``--format json`` for tools (:mod:`cfgplan.cli.errors`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from cfgplan.check import check as run_checks
from cfgplan.cli.app import EXIT_INPUT, app, report
from cfgplan.cli.options import DomainArg, choice_of, completing, errors_as_json, print_errors
from cfgplan.diagnostics import printable
from cfgplan.syntax.reader import read_domain, read_state

FORMATS = ("text", "json")


@app.command(short_help="Check a domain (and a state with its goal) without planning.")
def check(
    domain: DomainArg,
    state: Annotated[
        Path | None,
        typer.Argument(metavar="STATE", help="State file: facts, media, optional (goal ...)."),
    ] = None,
    format_: Annotated[
        str,
        typer.Option(
            "--format",
            metavar="|".join(FORMATS),
            parser=choice_of(FORMATS, "a format"),
            autocompletion=completing(FORMATS),
            help="text: the summary line on stdout (default); json: one JSON object on "
            "stdout, the errors or the summary (the messages stay on stderr).",
            show_default=False,
        ),
    ] = "text",
) -> None:
    """Check a domain (and a state with its goal) without planning.

    Prints every error and warning as file:line:col with the source line;
    exits 1 when there is an error (warnings alone do not fail). With
    --format json, stdout also holds one JSON object: the errors, or the
    summary with the warnings.
    """
    with errors_as_json(format_):
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
            print_errors(diagnostics)  # on stdout too, with --format json
            raise typer.Exit(EXIT_INPUT)
    versions = len(parsed.methods)
    methods = len({m.name.signature for m in parsed.methods})
    if format_ == "json":
        from cfgplan.cli.errors import CheckDocument, DiagnosticEntry, dump

        document = CheckDocument(
            ok=True,
            domain=str(domain),
            functionalities=len(parsed.functionalities),
            methods=methods,
            versions=versions,
            state=None if state is None else str(state),
            facts=None if world is None else len(world.facts),
            media=None if world is None else len(world.media),
            goal=None if world is None or world.goal is None else str(world.goal.call),
            warnings=[DiagnosticEntry.of(d) for d in diagnostics],
        )
        typer.echo(dump(document), nl=False)
        return
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
