"""The ``cfgplan`` command: a thin typer layer over the pipeline.

Exit codes: 0 success; 1 invalid input (a ``file:line:col`` message, never a
traceback); 2 usage; 3 no admissible configuration.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import typer

from cfgplan.diagnostics import CfgplanError, Diagnostic, render_all

app = typer.Typer(
    name="cfgplan",
    help="Plan-based configuration of robot societies (R. Lundh, 2006).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

EXIT_INPUT = 1
EXIT_NONE = 3

_extra_sources: dict[str, str] = {}


def remember_source(name: str, text: str) -> None:
    """Text to quote in messages for a source that is not a file (``--goal``)."""
    _extra_sources[name] = text


def _sources(diagnostics: list[Diagnostic]) -> dict[str, str]:
    sources = dict(_extra_sources)
    for d in diagnostics:
        if d.span is not None and d.span.file not in sources:
            with contextlib.suppress(OSError):
                sources[d.span.file] = Path(d.span.file).read_bytes().decode("utf-8", "replace")
    return sources


def report(diagnostics: list[Diagnostic]) -> None:
    """Print diagnostics on stderr, compiler style."""
    if diagnostics:
        print(render_all(diagnostics, _sources(diagnostics)), file=sys.stderr)


def say(text: str) -> None:
    """A plain line (or lines) on stderr: notes, progress, explanations."""
    print(text, file=sys.stderr, flush=True)


def write_output(text: str, output: Path | None, force: bool) -> None:
    """Write to ``output`` (refusing to overwrite without --force) or stdout."""
    if output is None:
        sys.stdout.write(text)
        return
    if output.exists() and not force:
        raise CfgplanError([Diagnostic("error", f"{output} exists; pass --force to overwrite it")])
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise CfgplanError(
            [Diagnostic("error", f"cannot write {output}: {exc.strerror}")]
        ) from None


def main() -> None:
    """Entry point of the console script."""
    from cfgplan.cli import commands  # noqa: F401  (registers the commands)

    try:
        app()
    except CfgplanError as exc:
        report(exc.diagnostics)
        sys.exit(EXIT_INPUT)
    except KeyboardInterrupt:
        print("cfgplan: interrupted", file=sys.stderr)
        sys.exit(130)
