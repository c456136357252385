"""``cfgplan run DOMAIN STATE --impl IMPL``: execute a configuration (chapter 5).

The configuration of the given rank is sorted, divided and wired as for
``cfgplan emit``, then run: every robot in this process (global channels
joined by the in-process transport), or with ``--robot NAME`` that robot's
part alone, its global channels over Zenoh to the other robots' programs
(``cfgplan run --robot`` or the emitted ``emil.py``, on this host or others).
The options are those of the emitted programs (:mod:`cfgplan.runtime.main`);
printed: what each action functionality received (``--verbose``: every
call), robots seen and lost, stale inputs, failures, then per functionality
how often it ran.
"""

from __future__ import annotations

import math
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.cli.app import app
from cfgplan.cli.emit import RankOpt, choose, title
from cfgplan.cli.plan import DomainArg, GoalsOpt, StateArg, WeightsOpt, load_problem
from cfgplan.cli.sequence import first_step
from cfgplan.diagnostics import CfgplanError, Diagnostic
from cfgplan.ir.model import Span
from cfgplan.reconfigure.setup import Settings, hooks
from cfgplan.runtime import Registry, RunError, RunOptions, Society, build, execute, society
from cfgplan.runtime.executor import DEFAULT_BUDGET
from cfgplan.runtime.faults import parse_injection
from cfgplan.runtime.main import open_transport
from cfgplan.runtime.monitor import HOLD
from cfgplan.runtime.part import Part
from cfgplan.runtime.tracefile import TraceFile, open_trace
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.zenoh_transport import (
    DEFAULT_LEASE,
    DEFAULT_SOCIETY,
    ZenohOptions,
    endpoint_problem,
)


class TransportKind(StrEnum):
    zenoh = "zenoh"
    inprocess = "inprocess"


def _positive(value: float | None) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise typer.BadParameter(f"{value}: must be a number more than 0")
    return value


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise typer.BadParameter(f"{value}: must be a finite number")
    return value


def _endpoints(values: list[str] | None) -> list[str] | None:
    for text in values or ():
        problem = endpoint_problem(text)
        if problem:
            raise typer.BadParameter(problem)
    return values


def _injections(values: list[str] | None) -> list[str] | None:
    for text in values or ():
        try:
            parse_injection(text)
        except RunError as exc:
            raise typer.BadParameter(exc.message + (f" ({exc.hint})" if exc.hint else "")) from None
    return values


def diagnostic(exc: RunError) -> CfgplanError:
    """A runtime error as the CLI reports errors (file:line:col and a caret when it has a place)."""
    span = None
    if exc.file is not None and exc.line is not None:
        column = exc.column or 1
        span = Span(
            file=exc.file, line=exc.line, column=column, end_line=exc.line, end_column=column + 1
        )
    return CfgplanError([Diagnostic("error", exc.message, span, exc.hint)])


@app.command()
def run(
    domain: DomainArg,
    state: StateArg,
    impl: Annotated[
        str,
        typer.Option(
            "--impl",
            help="Implementations: a module name (pkg.impl) or a .py file declaring them "
            "with @functionality (cfgplan.runtime).",
        ),
    ],
    goal: GoalsOpt = None,
    rank: RankOpt = 1,
    weights: WeightsOpt = None,
    robot: Annotated[
        str | None,
        typer.Option("--robot", help="Run only this robot's part (default: every robot)."),
    ] = None,
    transport: Annotated[
        TransportKind | None,
        typer.Option(
            "--transport",
            help="zenoh: reach the other robots' programs (the default with --robot); "
            "inprocess: robots of this process only (the default without --robot).",
        ),
    ] = None,
    society_name: Annotated[
        str, typer.Option("--society", help="Keeps societies on one network apart.")
    ] = DEFAULT_SOCIETY,
    listen: Annotated[
        list[str] | None,
        typer.Option(
            "--listen",
            metavar="ENDPOINT",
            callback=_endpoints,
            help="Listen on ENDPOINT (repeatable).",
        ),
    ] = None,
    connect: Annotated[
        list[str] | None,
        typer.Option(
            "--connect",
            metavar="ENDPOINT",
            callback=_endpoints,
            help="Connect to ENDPOINT (repeatable); with --listen or --connect, multicast "
            "scouting is off.",
        ),
    ] = None,
    zenoh_config: Annotated[
        Path | None,
        typer.Option("--zenoh-config", metavar="FILE", help="A Zenoh configuration file (JSON5)."),
    ] = None,
    lease: Annotated[
        float | None,
        typer.Option(
            "--lease",
            callback=_positive,
            help="Seconds after which a frozen robot is reported lost "
            f"(default {DEFAULT_LEASE:g}).",
        ),
    ] = None,
    rate: Annotated[
        float,
        typer.Option(
            "--rate",
            min=0,
            callback=_finite,
            help="Cycles per second for functionalities without :freq (0: every "
            "functionality in every cycle, no pause).",
        ),
    ] = 10.0,
    cycles: Annotated[
        int, typer.Option("--cycles", min=0, help="Stop after N cycles (0: no limit).")
    ] = 0,
    duration: Annotated[
        float | None,
        typer.Option("--duration", callback=_positive, help="Stop after S seconds."),
    ] = None,
    stale_periods: Annotated[
        float,
        typer.Option(
            "--stale-periods",
            callback=_positive,
            help="An input not refreshed for K periods of its sender is stale.",
        ),
    ] = 3.0,
    budget: Annotated[
        float,
        typer.Option(
            "--budget",
            min=0,
            callback=_finite,
            help="Seconds one call may take before it is reported as blocked (0: no budget).",
        ),
    ] = DEFAULT_BUDGET,
    trace: Annotated[
        Path | None,
        typer.Option("--trace", metavar="FILE", help="Write every event to FILE as JSON lines."),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite the --trace FILE if it exists.")
    ] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", help="Print every call, not only what actions received.")
    ] = False,
    inject: Annotated[
        list[str] | None,
        typer.Option(
            "--inject",
            metavar="FAULT",
            callback=_injections,
            help="A scripted fault (repeatable): 'fail compass(Emil) at cycle 20', 'at 2.5s', "
            "'recover compass(Emil) at ...', 'kill Emil at ...', 'retract (compass Emil) at ...'.",
        ),
    ] = None,
    reconfigure: Annotated[
        bool,
        typer.Option(
            "--reconfigure/--no-reconfigure",
            help="Monitor the run and switch configurations when a resource fails (5.5); "
            "--no-reconfigure runs the one configuration, as the thesis does.",
        ),
    ] = True,
    hold: Annotated[
        float,
        typer.Option(
            "--hold",
            callback=_positive,
            help="Seconds a failed resource must work again before it counts as recovered "
            "(doubled at each further failure).",
        ),
    ] = HOLD,
    margin: Annotated[
        float,
        typer.Option(
            "--margin",
            min=0,
            callback=_finite,
            help="A running configuration is left for a cheaper one only when the cost falls "
            "by this share of it (and by 1 at least).",
        ),
    ] = 0.1,
) -> None:
    """Execute a configuration: every robot in this process, or one robot on the network
    (thesis 5.2, 5.3).

    Runs until interrupted (Ctrl-C or SIGTERM), or --cycles or --duration, or
    until the action's task is accomplished. Watches the run and switches to
    another configuration when a resource fails (5.5), unless --no-reconfigure.
    Exit codes: 0 ran, 1 invalid input or a failing implementation, 2 usage, 3 no
    configuration of that rank, or none left at the end of the run.
    """
    kind = transport or (TransportKind.zenoh if robot is not None else TransportKind.inprocess)
    if robot is None and kind is TransportKind.zenoh:
        raise typer.BadParameter(
            "runs one robot per process: give --robot NAME", param_hint="'--transport zenoh'"
        )
    problem = load_problem(domain, state, goal, weights, sequence=True)
    config = first_step(problem, rank) if len(problem.goals) > 1 else choose(problem, rank)
    parts = [runtime_part(p) for p in deploy(config, problem.domain)]
    options = RunOptions(
        rate=rate,
        cycles=cycles,
        duration=duration,
        stale_periods=stale_periods,
        budget=budget or None,
        trace=None if trace is None else str(trace),
        force=force,
        verbose=verbose,
    )
    settings = Settings(
        tuple(parse_injection(t) for t in inject or ()), reconfigure, hold, margin
    )
    opened: Transport | None = None
    written: TraceFile | None = None
    try:
        registry = Registry.load(impl)
        if robot is None:
            running = society(parts, registry)
        else:
            part = next((p for p in parts if p.robot == robot), None)
            agents = {f[1] for f in problem.task.facts if f[0] in ("robot", "device")}
            if part is None and not (reconfigure and robot in agents):
                names = ", ".join(p.robot for p in parts)
                raise RunError(f"no robot {robot} in this configuration (its robots: {names})")
            part = part or Part(robot, (), ())  # a robot of the state: it waits for a part
            registry.require(c.name for c in part.calls)
            zenoh = ZenohOptions(
                society=society_name,
                listen=tuple(listen or ()),
                connect=tuple(connect or ()),
                config_file=None if zenoh_config is None else str(zenoh_config),
                lease=lease,
            )
            opened = open_transport(robot, kind.value, zenoh)
            shared = opened if isinstance(opened, InProcessTransport) else None
            running = Society([build(part, registry, opened)], shared)
        if options.trace is not None:
            written = open_trace(options.trace, options.force)
        adapting = hooks(
            running, registry, problem, config, parts, settings, written, whole=robot is None
        )
        names = ", ".join(r.name for r in running.robots)
        typer.echo(f"{title(problem, config, rank)}: {names}; {_how_long(options)}")
        code = execute(
            running, options, source=registry.source, trace=written, hooks=adapting
        )
    except RunError as exc:
        if opened is not None:
            opened.close()
        if written is not None:
            written.close()
        raise diagnostic(exc) from None
    if code:
        raise typer.Exit(code)


def _how_long(options: RunOptions) -> str:
    limits = []
    if options.cycles:
        limits.append(f"{options.cycles} cycle(s)")
    if options.duration is not None:
        limits.append(f"{options.duration:g} s")
    return " or ".join(limits) if limits else "until interrupted"
