"""``cfgplan record TRACE -o RUN.mcap``: a run's trace as an MCAP file for Foxglove.

The trace is what ``cfgplan run --trace TRACE`` wrote (a robot program's
``--trace``, a simulation's ``trace.jsonl``); when it rotated, ``TRACE.1``
(the events just before) is read first. The conversion is
:mod:`cfgplan.record.mcap_export`: one channel per kind of event, JSON
messages, JSON Schemas from :mod:`cfgplan.runtime.schema`. It needs the
``mcap`` package (``pip install 'cfgplan[record]'``), imported only here, as
the command runs: a robot that only runs its program needs none of it.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

from pathlib import Path
from types import ModuleType
from typing import Annotated

import typer

from cfgplan.cli.app import say
from cfgplan.cli.options import ForceOpt
from cfgplan.cli.registry import command
from cfgplan.diagnostics import error, run_error
from cfgplan.files import check_target, write_file
from cfgplan.runtime.errors import RunError

INSTALL = "pip install 'cfgplan[record]'"
"""How to get what recording needs."""

_NEEDED = ("mcap", "zstandard", "lz4")


def load_exporter() -> ModuleType:
    """:mod:`cfgplan.record.mcap_export`, or a clear error naming the extra to
    install when the ``mcap`` package (or a compressor it uses) is missing."""
    try:
        from cfgplan.record import mcap_export
    except ModuleNotFoundError as exc:
        if exc.name is None or exc.name.split(".")[0] not in _NEEDED:
            raise
        raise error(
            f"cfgplan record needs the {exc.name.split('.')[0]} package, which is not installed",
            hint=f"install it with: {INSTALL}",
        ) from None
    return mcap_export


@command(short_help="Turn a run's trace into an MCAP file that Foxglove opens.")
def record(
    trace: Annotated[
        Path,
        typer.Argument(
            metavar="TRACE",
            help="A trace of cfgplan run --trace (JSON lines); TRACE.1, when there, is read first.",
            show_default=False,
        ),
    ],
    output: Annotated[
        Path,
        typer.Option("--output", "-o", metavar="FILE", help="The MCAP file to write (.mcap)."),
    ],
    force: ForceOpt = False,
) -> None:
    """Turn the trace of a run (cfgplan run --trace TRACE) into an MCAP file that
    Foxglove opens: one channel per kind of event (/cfgplan/ROBOT/calls,
    /cfgplan/ROBOT/channels/CHANNEL/sent and /received, /cfgplan/switches,
    /cfgplan/failures, ...), JSON messages with a JSON Schema per channel, each
    at the event's time. The same trace always gives the same bytes.

    Exit codes: 0 written, 1 a trace line that is not an event (file:line), a
    file that cannot be read or written, or FILE exists without --force; 2 usage.
    """
    check_target(output, force)  # before reading: refuse at once
    exporter = load_exporter()
    files = exporter.trace_files(trace)
    if any(output.resolve() == f.resolve() for f in files):
        raise error(f"{output} is the trace itself; give another -o file")
    try:
        data, done = exporter.convert(files)
    except RunError as exc:
        raise run_error(exc) from None
    write_file(output, data, force)
    read = " then ".join(str(p) for p in files)
    say(f"wrote {output}: {done.total} message(s) on {len(done.messages)} channel(s) from {read}")
