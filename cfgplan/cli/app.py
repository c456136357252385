"""The ``cfgplan`` command: a thin typer layer over the pipeline.

Exit codes: 0 success; 1 invalid input (a ``file:line:col`` message, never a
traceback), an output that cannot be written (a full disk) or memory running
out; 2 usage; 3 no admissible configuration.

This module is the entry point and loads nothing heavy itself: ``cfgplan
--version`` and the top-level help (``--help``, ``-h``, bare ``cfgplan``) are
answered by :func:`main` before typer, pydantic or Lark are imported (the help
text is pre-rendered from the typer app, :mod:`cfgplan.cli.help_text`); any
other command line loads the typer app (:mod:`cfgplan.cli.root`, also reached
as ``cfgplan.cli.app.app``) and the module of the command it names
(:func:`register`, by the one map of commands, :mod:`cfgplan.cli.registry`),
and the libraries that command needs, as it runs.
"""

from __future__ import annotations

import contextlib
import gc
import importlib
import os
import sys
from contextvars import ContextVar

from cfgplan.cli.registry import COMMANDS, QUICK_EXIT, module_of, version_line

__all__ = ["COMMANDS", "QUICK_EXIT", "command_of", "console", "main", "register", "version_line"]

TYPE_CHECKING = False  # as typing.TYPE_CHECKING, without importing typing (3 ms)
if TYPE_CHECKING:
    from pathlib import Path
    from typing import Any, NoReturn

    from cfgplan.cli.root import app as app
    from cfgplan.diagnostics import Diagnostic


def __getattr__(name: str) -> Any:
    """``app``, the typer application (:mod:`cfgplan.cli.root`), loaded when a
    command module or a test first asks for it (PEP 562)."""
    if name == "app":
        from cfgplan.cli.root import app

        return app
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


EXIT_INPUT = 1
EXIT_NONE = 3

_extra_sources: dict[str, str] = {}


def remember_source(name: str, text: str) -> None:
    """Text to quote in messages for a source that is not a file (``--goal``)."""
    _extra_sources[name] = text


def _sources(diagnostics: list[Diagnostic]) -> dict[str, str]:
    from cfgplan.diagnostics import CfgplanError
    from cfgplan.files import read_source
    from cfgplan.syntax.reader import decode

    sources = dict(_extra_sources)
    for d in diagnostics:
        if d.span is not None and d.span.file not in sources:
            with contextlib.suppress(CfgplanError):
                data = read_source(d.span.file)
                sources[d.span.file] = decode(data, d.span.file, quoting=True)
    return sources


def report(diagnostics: list[Diagnostic]) -> None:
    """Print diagnostics on stderr, compiler style."""
    if diagnostics:
        from cfgplan.diagnostics import render_all

        print(render_all(diagnostics, _sources(diagnostics)), file=sys.stderr)


def say(text: str) -> None:
    """A plain line (or lines) on stderr: notes, progress, explanations; what
    came from the input is shown with control characters escaped."""
    from cfgplan.diagnostics import printable

    print(printable(text, keep="\n"), file=sys.stderr, flush=True)


def usage_error(message: str, option: str) -> NoReturn:
    """Refuse the command line (exit 2), naming the option at fault."""
    import typer

    raise typer.BadParameter(message, param_hint=f"'{option}'")


def write_output(text: str, output: Path | None, force: bool) -> None:
    """Write to ``output`` (refusing to overwrite without --force, never through
    a link, see :mod:`cfgplan.files`) or to stdout."""
    if output is None:
        sys.stdout.write(text)
        return
    from cfgplan.files import write_file

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
    from cfgplan.diagnostics import Diagnostic

    with contextlib.suppress(OSError, ValueError):
        report([Diagnostic("error", message, None, hint)])
    sys.exit(EXIT_INPUT)


def _run() -> int | str | None:
    """Run the command; stdout is flushed here, so that a write error (a full
    disk, ``> /dev/full``) is reported rather than raised at exit."""
    from cfgplan.cli import app as this  # its ``app``: the typer app, or what replaced it

    try:
        this.app(prog_name="cfgplan")  # also as python -m cfgplan
        status: int | str | None = 0
    except SystemExit as exc:
        status = exc.code
    sys.stdout.flush()
    return status


def command_of(args: list[str]) -> str | None:
    """The command a command line names: its first word that is not an option."""
    return next((a for a in args if not a.startswith("-")), None)


def register(args: list[str]) -> None:
    """Import the module of the command ``args`` name, and only that one: ``cfgplan
    plan`` need not load the runtime, Graphviz or the simulator (a fifth of its
    start-up). Help, shell completion and a mistyped name load what they need
    as they run (the root group loads commands lazily: :mod:`cfgplan.cli.registry`)."""
    name = command_of(args)
    if name in COMMANDS and "_CFGPLAN_COMPLETE" not in os.environ:
        importlib.import_module(module_of(name))


def _fast(args: list[str]) -> int | None:
    """Answer ``--version`` and the top-level help without loading typer: the
    exit status, or None when the command line needs the typer app. The help
    is the text typer renders at :data:`cfgplan.cli.help_text.WIDTH` columns,
    so it is used only where click would render it that wide (a terminal at
    least as wide, or no terminal); shell completion always goes to typer."""
    if "_CFGPLAN_COMPLETE" in os.environ:
        return None
    if args == ["--version"]:
        sys.stdout.write(version_line() + "\n")
        return 0
    if args not in ([], ["--help"], ["-h"]):
        return None
    import shutil

    from cfgplan.cli import help_text

    if shutil.get_terminal_size().columns < help_text.WIDTH:
        return None
    if not args:  # as click's no_args_is_help: the help on stderr, a usage error
        sys.stderr.write(help_text.HELP)
        return 2
    sys.stdout.write(help_text.HELP)
    return 0


def _load(args: list[str]) -> None:
    """:func:`register` the command ``args`` name, with the cyclic garbage
    collector paused while its modules load (they make tens of thousands of
    objects, and no garbage worth collecting); then freeze what they made
    (:func:`gc.freeze`): classes, functions and schemas that live as long as the
    process are never traversed again, by collections while the command runs
    nor by the last one at exit. ``cfgplan plan`` took a fifth less time (75 of
    350 ms, most of it at exit). A process running several command lines
    (the fuzzing worker, a test) freezes what it holds at the first only."""
    enabled, first = gc.isenabled(), gc.get_freeze_count() == 0
    gc.disable()
    try:
        register(args)
    finally:
        if first:
            gc.freeze()
        if enabled:
            gc.enable()


def _answer(args: list[str]) -> int | str | None:
    """Run the command line ``args``: the exit status. A :class:`CfgplanError`
    is reported here (exit 1)."""
    status = _fast(args)
    if status is not None:
        sys.stdout.flush()
        return status
    _load(args)
    from cfgplan.diagnostics import CfgplanError  # loaded by every command

    try:
        return _run()
    except CfgplanError as exc:
        report(exc.diagnostics)
        return EXIT_INPUT


ONE_COMMAND: ContextVar[bool] = ContextVar("one_command", default=False)
"""Whether this process runs one command and exits (the console script,
:func:`main`), not many in a row (tests, a program that embeds the app):
then :func:`cfgplan.cli.options.load_problem` freezes what it read out of
the cycle collector's sight (:func:`gc.freeze`)."""


def main() -> None:
    """Entry point of the console script."""
    sys.unraisablehook = _unraisable
    ONE_COMMAND.set(True)
    try:
        status = _answer(sys.argv[1:])
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


def console() -> NoReturn:
    """The console script and ``python -m cfgplan``: :func:`main`, then, for
    a :data:`QUICK_EXIT` command, the process ends at once (:func:`_leave`) —
    unless a profiler or a coverage tool watches it (``python -m cProfile``,
    ``coverage run``), which writes what it found when the interpreter ends.
    (:func:`main` itself only raises SystemExit: tests call it in process.)"""
    try:
        main()
    except SystemExit as done:
        watched = sys.gettrace() is not None or sys.getprofile() is not None
        if command_of(sys.argv[1:]) in QUICK_EXIT and not watched:
            _leave(done.code)
        raise
    sys.exit(0)  # pragma: no cover - main() always raises SystemExit


def _leave(status: int | str | None) -> NoReturn:
    """End the process with ``status`` as :func:`sys.exit` reads it (None: 0; a
    text: printed to stderr, 1), without the interpreter's teardown, which
    frees every object one by one: after a large search that is work for
    nothing (chain D=200, 120 MiB: 60 ms of its 1.2 s; mypy's fast exit does
    the same). Only for :data:`QUICK_EXIT` commands, which leave nothing to
    close but stdout and stderr, flushed here (stdout was flushed, and a
    failure to write it reported, when the command returned: :func:`_run`)."""
    if status is None:
        code = 0
    elif isinstance(status, int):
        code = status
    else:
        with contextlib.suppress(OSError, ValueError):
            print(status, file=sys.stderr)
        code = 1
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(code)
