"""``cfgplan simulate EXPERIMENT --out DIR``: a scenario run in the 2-D simulator.

EXPERIMENT is ``cross-door``, ``carry-bar`` or ``build-wall`` (the thesis's
experiments, chapter 6) or a scenario file (docs/how-to/write-a-scenario.md). The
configurations are planned, run on :mod:`cfgplan.runtime` in simulated time,
monitored and reconfigured; DIR receives ``summary.json``, ``trace.jsonl``
and the pictures. The simulator itself (:mod:`cfgplan.sim`) is imported
only here, when the command runs: it needs the ``sim`` extra.

Exit codes: 0 the task was accomplished; 1 invalid input (or the ``sim``
extra missing); 2 usage; 3 no admissible configuration (at the start, or
none left at the end); 4 the run ended without accomplishing the task (the
bar fell, a block is not aligned, time ran out); 130 interrupted.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

import importlib
import sys
from pathlib import Path
from typing import Annotated, TextIO, cast

import typer

from cfgplan.cli.app import EXIT_INPUT, EXIT_NONE, report
from cfgplan.cli.options import count_of, number_of
from cfgplan.cli.registry import command
from cfgplan.diagnostics import CfgplanError, error, run_error
from cfgplan.runtime.options import RECORD, RECORD_MAX_BYTES

EXIT_FAILED = 4
EXIT_INTERRUPTED = 130


def _need_extra() -> None:
    for module in ("numpy", "shapely", "matplotlib"):
        try:
            importlib.import_module(module)
        except ImportError:
            raise error(
                f"cfgplan simulate needs {module}, which is not installed",
                hint="install the simulator's extra: pip install 'cfgplan[sim]'",
            ) from None


@command(short_help="Run a thesis experiment in the 2-D simulator (chapter 6).")
def simulate(
    experiment: Annotated[
        Path,
        typer.Argument(
            metavar="EXPERIMENT",
            help="cross-door, carry-bar, build-wall (the thesis's experiments), "
            "or a scenario file (.toml).",
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            "-o",
            metavar="DIR",
            help="Folder for summary.json, trace.jsonl and the pictures.",
        ),
    ],
    seed: Annotated[
        int | None,
        typer.Option(
            "--seed",
            metavar="N",
            parser=count_of(0),
            help="Seed of the noise (default: the scenario's).",
        ),
    ] = None,
    duration: Annotated[
        float | None,
        typer.Option(
            "--duration",
            metavar="S",
            parser=number_of(0, above=True),
            help="Simulated seconds at most (default: the scenario's).",
        ),
    ] = None,
    rank: Annotated[
        int | None,
        typer.Option(
            "--rank",
            metavar="N",
            parser=count_of(1),
            help="Start with the configuration (or sequence) of this rank, 1 being the cheapest "
            "(default: the scenario's, else 1).",
        ),
    ] = None,
    animate: Annotated[
        bool, typer.Option("--animate", help="Also write animation.gif (no system package needed).")
    ] = False,
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite the outputs of an earlier run in --out.")
    ] = False,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="Print only the outcome, not the run's events.")
    ] = False,
    record: Annotated[
        Path | None,
        typer.Option(
            "--record",
            metavar="FILE",
            help=RECORD.help,
            show_default=False,
        ),
    ] = None,
    record_max_bytes: Annotated[
        int,
        typer.Option(
            "--record-max-bytes",
            metavar="N",
            parser=count_of(0),
            help=RECORD_MAX_BYTES.help,
            show_default=False,
        ),
    ] = RECORD_MAX_BYTES.default,
) -> None:
    """Simulate a thesis experiment in 2-D: run, fail, reconfigure (chapter 6).

    Exit codes: 0 accomplished, 1 invalid input, 2 usage, 3 no admissible
    configuration, 4 not accomplished, 130 interrupted.
    """
    try:
        _need_extra()
        from cfgplan.runtime.errors import RunError
        from cfgplan.sim.outputs import prepare as prepare_folder
        from cfgplan.sim.run import open_scenario, prepare

        try:
            ready = prepare(open_scenario(str(experiment)))
        except RunError as exc:  # the implementations cannot be loaded
            raise run_error(exc) from None
        prepare_folder(out, force)
        recording = None
        if record is not None:  # mcap is imported only then (cfgplan.record)
            from cfgplan.record.launch import start_recording
            from cfgplan.record.policy import Policy

            try:
                recording = start_recording(record, force, Policy(max_bytes=record_max_bytes))
            except RunError as exc:
                raise run_error(exc) from None
        try:
            code = _run(ready, out, seed, duration, rank, animate, quiet, recording)
        finally:
            if recording is not None:
                recording.close()
        if recording is not None and recording.failed:
            raise error(recording.failed)
    except CfgplanError as exc:
        report(exc.diagnostics)
        raise typer.Exit(EXIT_INPUT) from None
    if code:
        raise typer.Exit(code)


def _run(
    ready: object,
    out: Path,
    seed: int | None,
    duration: float | None,
    rank: int | None,
    animate: bool,
    quiet: bool,
    recording: object = None,
) -> int:
    from cfgplan.runtime.console import Printer
    from cfgplan.runtime.errors import RunError
    from cfgplan.sim.outputs import write_all
    from cfgplan.sim.report import why
    from cfgplan.sim.run import Prepared
    from cfgplan.sim.run import simulate as run_simulation

    assert isinstance(ready, Prepared)
    loaded = ready.loaded
    s = loaded.scenario
    # a console that goes away (a closed pipe) is given up, never fatal
    console = Printer(False, "", sys.stdout, sys.stderr)
    echo = console.say
    if not quiet:
        echo(f"{s.name}: {s.title or loaded.file}")
    try:
        with (out / "trace.jsonl").open("w", encoding="utf-8", newline="\n") as written:
            trace: TextIO = written
            if recording is not None:  # each trace line recorded too (cfgplan.record.live)
                from cfgplan.record.live import LiveRecorder, Tee

                assert isinstance(recording, LiveRecorder)
                trace = cast(TextIO, Tee(written, recording))
            run = run_simulation(
                ready,
                seed=seed,
                duration=duration,
                rank=rank,
                trace=trace,
                echo=None if quiet else echo,
            )
    except OSError as exc:
        raise error(f"cannot write {out / 'trace.jsonl'}: {exc.strerror}") from None
    except RunError as exc:
        raise run_error(exc) from None
    try:
        files = write_all(run, out, animate)
    except OSError as exc:
        raise error(f"cannot write in {out}: {exc.strerror}") from None
    reasons = why(run)
    if not reasons:
        echo(f"accomplished in {run.world.time:g} s (seed {run.world.seed})")
    else:
        console.say("not accomplished: " + reasons[0], sys.stderr)
        for line in reasons[1:]:
            console.say("  " + line, sys.stderr)
    if not quiet:
        echo(f"wrote {', '.join(files)} in {out}")
    if run.ended == "interrupted":
        return EXIT_INTERRUPTED
    if not reasons:
        return 0
    return EXIT_NONE if run.stopped else EXIT_FAILED
