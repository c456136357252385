"""The ``cfgplan`` command: a thin typer layer over the pipeline.

Exit codes: 0 success; 1 invalid input (a ``file:line:col`` message, never a
traceback), an output that cannot be written (a full disk) or memory running
out; 2 usage; 3 no admissible configuration.
"""

from __future__ import annotations

import contextlib
import gc
import importlib
import os
import sys
from collections.abc import Callable
from importlib.metadata import version
from pathlib import Path
from typing import Annotated, Any, NoReturn, TypeVar

import typer
from typer.core import TyperCommand

from cfgplan.diagnostics import CfgplanError, Diagnostic, printable, render_all
from cfgplan.files import read_source, write_file
from cfgplan.syntax.reader import decode


class Command(TyperCommand):
    """A cfgplan command: its usage line names the arguments as ``DOMAIN
    STATE`` (typer would write ``{DOMAIN} {STATE}``)."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        pieces: list[str] = super().collect_usage_pieces(ctx)
        return [p[1:-1] if p.startswith("{") and p.endswith("}") else p for p in pieces]


_F = TypeVar("_F", bound=Callable[..., Any])


class _Typer(typer.Typer):
    """Every command is a :class:`Command`."""

    def command(self, *args: Any, **kwargs: Any) -> Callable[[_F], _F]:
        kwargs.setdefault("cls", Command)
        return super().command(*args, **kwargs)


app = _Typer(
    name="cfgplan",
    help="Plan-based configuration of robot societies (R. Lundh, 2006).",
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"cfgplan {version('cfgplan')}")
        raise typer.Exit(0)


@app.callback()
def _options(
    show_version: Annotated[
        bool,
        typer.Option(
            "--version", is_eager=True, callback=_version, help="Print cfgplan's version and exit."
        ),
    ] = False,
) -> None:
    """Plan-based configuration of robot societies (R. Lundh, 2006): plan, draw,
    emit and run configurations of robots lending each other functionalities."""

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
            with contextlib.suppress(CfgplanError):
                sources[d.span.file] = decode(read_source(d.span.file), d.span.file)
    return sources


def report(diagnostics: list[Diagnostic]) -> None:
    """Print diagnostics on stderr, compiler style."""
    if diagnostics:
        print(render_all(diagnostics, _sources(diagnostics)), file=sys.stderr)


def say(text: str) -> None:
    """A plain line (or lines) on stderr: notes, progress, explanations; what
    came from the input is shown with control characters escaped."""
    print(printable(text, keep="\n"), file=sys.stderr, flush=True)


def usage_error(message: str, option: str) -> NoReturn:
    """Refuse the command line (exit 2), naming the option at fault."""
    raise typer.BadParameter(message, param_hint=f"'{option}'")


def write_output(text: str, output: Path | None, force: bool) -> None:
    """Write to ``output`` (refusing to overwrite without --force, never through
    a link, see :mod:`cfgplan.files`) or to stdout."""
    if output is None:
        sys.stdout.write(text)
        return
    write_file(output, text.encode("utf-8"), force)


def _caused_by_memory(exc: BaseException) -> bool:
    """True when ``exc`` is, or was raised while handling, a MemoryError (C code
    running out of memory sometimes surfaces as a SystemError)."""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, MemoryError):
            return True
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return False


def _unraisable(unraisable: Any) -> None:
    """Generators closed while a MemoryError unwinds the stack may fail again
    for want of memory, and Python prints each as "Exception ignored": the one
    "out of memory" message says it all. Anything else is printed as usual."""
    if isinstance(unraisable.exc_value, MemoryError):
        return
    sys.__unraisablehook__(unraisable)


def _silence_stdout() -> None:
    """After stdout failed, point it at the null device so that the
    interpreter's last flush does not fail again."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)


_OUT_OF_MEMORY = "out of memory"


def _fail(message: str, hint: str | None = None) -> None:
    with contextlib.suppress(OSError, ValueError):
        report([Diagnostic("error", message, None, hint)])
    sys.exit(EXIT_INPUT)


def _run() -> int | str | None:
    """Run the command; stdout is flushed here, so that a write error (a full
    disk, ``> /dev/full``) is reported rather than raised at exit."""
    try:
        app(prog_name="cfgplan")  # also as python -m cfgplan
        status: int | str | None = 0
    except SystemExit as exc:
        status = exc.code
    sys.stdout.flush()
    return status


COMMANDS = ("check", "emit", "plan", "render", "run", "simulate")
"""Every command, each defined (and registered on :data:`app`) by the module
of its name, ``cfgplan.cli.<name>``; :mod:`cfgplan.cli.commands` imports them all."""


def register(args: list[str]) -> None:
    """Import the module of the command ``args`` name, and only that one: ``cfgplan
    plan`` need not load the runtime, Graphviz or the simulator (a fifth of its
    start-up). Every command for anything else: help, shell completion, a
    mistyped name (typer lists the commands)."""
    name = next((a for a in args if not a.startswith("-")), None)
    if name in COMMANDS and "_CFGPLAN_COMPLETE" not in os.environ:
        importlib.import_module(f"cfgplan.cli.{name}")
    else:
        importlib.import_module("cfgplan.cli.commands")


def main() -> None:
    """Entry point of the console script."""
    sys.unraisablehook = _unraisable
    try:
        register(sys.argv[1:])
        status = _run()
    except CfgplanError as exc:
        report(exc.diagnostics)
        sys.exit(EXIT_INPUT)
    except KeyboardInterrupt:
        print("cfgplan: interrupted", file=sys.stderr)
        sys.exit(130)
    except BrokenPipeError:  # cfgplan plan ... | head: the reader has all it wants
        _silence_stdout()
        sys.exit(EXIT_INPUT)
    except UnicodeEncodeError as exc:
        _silence_stdout()
        _fail(
            f"cannot write the output in this terminal's encoding ({exc.encoding}): "
            f"it cannot show {exc.object[exc.start : exc.end]!r}",
            "set PYTHONIOENCODING=utf-8, or write to a file with -o",
        )
    except OSError as exc:
        _silence_stdout()
        if exc.filename:
            _fail(f"{exc.filename}: {exc.strerror or exc}")
        _fail(f"cannot write the output: {exc.strerror or exc}")
    except (MemoryError, SystemError) as exc:
        if not _caused_by_memory(exc):
            raise
        status = _OUT_OF_MEMORY
    if status is _OUT_OF_MEMORY:
        # Reported only here, outside the except clause: the traceback, and with
        # it the frames holding what filled the memory, is gone by now.
        gc.collect()
        try:
            _fail(
                "out of memory",
                "the problem is too large for the memory available; "
                "plan fewer configurations (-k N, not --all) or set --time-limit",
            )
        except MemoryError:
            os.write(2, b"cfgplan: error: out of memory\n")
            sys.exit(EXIT_INPUT)
    sys.exit(status)
