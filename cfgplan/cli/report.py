"""``cfgplan report RUN [-o DIR]``: the pictures and one HTML page of any run.

RUN is what ``cfgplan run --trace`` or ``cfgplan simulate`` wrote (a trace,
several robots' traces, a simulation's folder) or an MCAP recording. DIR is by
default beside the run (:func:`default_folder`): ``run.jsonl`` is drawn in
``run-report/``, a simulation's folder ``out/cross-door`` in
``out/cross-door/report/``. The
work is :mod:`cfgplan.report` (matplotlib, from the ``sim`` extra; ``mcap``
for recordings), imported only as the command runs.

Exit codes: 0 written; 1 a file that cannot be read, is not a trace or a
recording, holds no event, or DIR holding an earlier report without
``--force``; 2 usage.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from cfgplan.cli.app import EXIT_INPUT, say
from cfgplan.cli.app import report as report_diagnostics
from cfgplan.cli.registry import command
from cfgplan.diagnostics import CfgplanError, error, run_error
from cfgplan.runtime.errors import RunError

if TYPE_CHECKING:
    from cfgplan.report.make import Made


def _need_matplotlib() -> None:
    try:
        importlib.import_module("matplotlib")
    except ImportError:
        raise error(
            "cfgplan report needs matplotlib, which is not installed",
            hint="install the simulator's extra: pip install 'cfgplan[sim]'",
        ) from None


def _prepare(folder: Path, force: bool) -> None:
    from cfgplan.report.make import report_files

    if folder.exists() and not folder.is_dir():
        raise error(f"{folder} exists and is not a folder")
    if folder.is_dir() and not force:
        found = report_files(folder)
        if found:
            more = ", ..." if len(found) > 3 else ""
            raise error(
                f"{folder} holds a report ({', '.join(found[:3])}{more}); "
                "pass --force to overwrite it"
            )
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if force:  # an earlier report's pictures go: none is left to mislead
            for name in report_files(folder):
                (folder / name).unlink()
    except OSError as exc:
        raise error(f"cannot write in {folder}: {exc.strerror}") from None


def default_folder(run: list[Path]) -> Path:
    """Where a report goes without ``-o``: for a folder (a simulation's), its
    ``report`` sub-folder; for a file, ``NAME-report`` beside the first one
    (``logs/run.jsonl``: ``logs/run-report``), so that a report never lands in
    whatever folder the command happened to be typed in."""
    first = run[0]
    if first.is_dir():
        return first / "report"
    return first.with_name(f"{first.stem or first.name}-report")


def _make(run: list[Path], out: Path, replay: bool, force: bool) -> "Made":
    _need_matplotlib()
    from cfgplan.report.make import ReportOptions, make_report

    _prepare(out, force)
    try:
        return make_report(run, out, ReportOptions(replay=replay))
    except RunError as exc:
        raise run_error(exc) from None
    except OSError as exc:
        raise error(f"cannot write in {out}: {exc.strerror}") from None


@command(short_help="Draw any run (a trace or an MCAP recording): pictures and a page.")
def report(
    run: Annotated[
        list[Path],
        typer.Argument(
            metavar="RUN",
            help="A trace of cfgplan run --trace or cfgplan simulate (JSON lines; several "
            "robots' traces are merged), a simulation's --out folder, or an MCAP recording.",
            show_default=False,
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            metavar="DIR",
            help="Folder for the pictures and report.html  [default: RUN-report beside a "
            "trace or a recording, RUN/report for a simulation's folder]",
            show_default=False,
        ),
    ] = None,
    replay: Annotated[
        bool,
        typer.Option(
            "--replay/--no-replay",
            help="For a simulation (summary.json beside the trace): run it again from its seed "
            "to draw the trajectories, if it gives the same trace.",
        ),
    ] = True,
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite an earlier report in DIR.")
    ] = False,
) -> None:
    """Draw a run: timeline.png (Fig. 6.5), configuration-N.png for each
    configuration, for a simulation trajectories.png (Fig. 6.6) and bar.png, and
    report.html: all of it in one page that opens offline (inline SVG).

    Exit codes: 0 written, 1 a file that cannot be read or is not a trace or a
    recording, or DIR holding a report without --force; 2 usage.
    """
    out = default_folder(run) if out is None else out
    try:
        made = _make(run, out, replay, force)
    except CfgplanError as exc:
        report_diagnostics(exc.diagnostics)
        raise typer.Exit(EXIT_INPUT) from None
    for note in made.notes:
        say(note)
    say(f"wrote {', '.join(made.files)} in {out}")
