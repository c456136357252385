"""``cfgplan check DOMAIN [STATE]``: read and check, report every problem
(thesis 4.4); ``--format json`` for tools (:mod:`cfgplan.cli.errors`)."""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

import re
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from cfgplan.check import check as run_checks
from cfgplan.check.messages import by_position
from cfgplan.cli.app import EXIT_INPUT, report
from cfgplan.cli.options import DomainArg, choice_of, completing, errors_as_json, print_errors
from cfgplan.cli.registry import command
from cfgplan.diagnostics import CfgplanError, Diagnostic, printable
from cfgplan.ir.model import Domain, State
from cfgplan.syntax.reader import (
    FormErrors,
    SourceFile,
    domain_from,
    parse,
    read_text_file,
    state_from,
)

FORMATS = ("text", "json")


class _Read:
    """What the files hold: the forms that read, the errors of those that did
    not, and the names those declare."""

    def __init__(self) -> None:
        self.errors: list[Diagnostic] = []
        self.unread: set[str] = set()

    def source(self, path: Path) -> SourceFile:
        """The file's forms; a wrong form is noted and the others kept (a
        syntax error, after which nothing reads, is raised)."""
        name, text = read_text_file(path)
        try:
            return parse(text, name)
        except FormErrors as exc:
            if exc.source is None:
                raise
            self.errors += exc.diagnostics
            self.unread.update(exc.unread)
            return exc.source

    def relevant(self, found: list[Diagnostic]) -> list[Diagnostic]:
        """The checker's findings but those about a name whose form did not
        read: they follow from its error (its ``:ouput`` wrong, every use of
        it would be "undefined")."""
        if not self.unread:
            return found
        names = "|".join(re.escape(n) for n in sorted(self.unread))
        about = re.compile(rf"(?<![\w?-])({names})(?![\w-])")
        return [d for d in found if not about.search(d.message)]


def _refuse(diagnostics: list[Diagnostic]) -> NoReturn:
    """Report every error and warning, then how many there are; exit 1."""
    report(diagnostics)
    errors = sum(1 for d in diagnostics if d.is_error)
    typer.echo(f"{errors} error(s), {len(diagnostics) - errors} warning(s)", err=True)
    print_errors(diagnostics)  # on stdout too, with --format json
    raise typer.Exit(EXIT_INPUT)


def read_and_check(
    domain: Path, state: Path | None
) -> tuple[Domain, State | None, list[Diagnostic]]:
    """Read both files and check them: every problem, a wrong form's and the
    checker's, by file position (4.4). A syntax error, which ends the
    reading of its file, is raised as a :class:`CfgplanError`."""
    read = _Read()
    parsed = domain_from(read.source(domain))
    world = None if state is None else state_from(read.source(state))
    found = read.relevant(run_checks(parsed, world, world.goal if world else None))
    files = [str(domain)] + ([] if state is None else [str(state)])
    return parsed, world, by_position([*read.errors, *found], files)


@command(short_help="Check a domain (and a state with its goal) without planning.")
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
        try:
            parsed, world, diagnostics = read_and_check(domain, state)
        except CfgplanError as exc:  # a syntax error: its file reads no further
            _refuse(exc.diagnostics)
        errors = sum(1 for d in diagnostics if d.is_error)
        warnings = len(diagnostics) - errors
        if errors:
            _refuse(diagnostics)
        report(diagnostics)
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
