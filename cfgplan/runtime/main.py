"""The command line of emitted programs: ``python emil.py`` and ``python run_all.py``.

A robot's module runs that robot alone (``robot_main``), by default on the
network through Zenoh, so that each robot runs its individual configuration
in its own process, as each ran on its own body in the thesis (5.2.2);
``run_all.py`` runs every robot in one process (``society_main``). Both take
the options of ``cfgplan run``: ``--impl``, ``--rate``, ``--cycles``,
``--duration``, ``--stale-periods``, ``--budget``, ``--trace FILE``
(``--force``), ``--verbose``, ``--inject FAULT``; a robot's module also
``--transport``, ``--society``, ``--listen``, ``--connect``,
``--zenoh-config`` and ``--lease``.

On the network a robot's module follows the coordinator (the robot that owns
the goal, run by ``cfgplan run --robot``, 5.5): it installs the parts it is
sent, reports what its monitor detects, and applies the scripted faults aimed
at it (``kill`` ends the process as a crash). It needs no planner.

Exit status: 0 ran, 1 user error or a failing functionality, 2 usage.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.executor import DEFAULT_BUDGET, Configure, Robot
from cfgplan.runtime.faults import Injection, parse_injection
from cfgplan.runtime.inject import Injector, Scripted
from cfgplan.runtime.launch import Hooks, RunOptions, execute
from cfgplan.runtime.member import Member, Membership
from cfgplan.runtime.monitor import Monitor
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.society import Society, assemble
from cfgplan.runtime.tracefile import TraceFile, open_trace
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.zenoh_transport import (
    DEFAULT_LEASE,
    DEFAULT_SOCIETY,
    ZenohOptions,
    endpoint_problem,
)

__all__ = ["KILLED", "crash", "robot_main", "society_main"]

KILLED = 137
"""Exit status of a process a scripted ``kill`` ended (as SIGKILL would)."""


def _number(low: float, strict: bool, what: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if value != value or value == float("inf") or value < low or (strict and value == low):
            raise argparse.ArgumentTypeError(f"{text!r}: {what}")
        return value

    return parse


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be 0 or more")
    return value


def _injection(text: str) -> Injection:
    try:
        return parse_injection(text)
    except RunError as exc:
        raise argparse.ArgumentTypeError(exc.message) from None


def _endpoint(text: str) -> str:
    problem = endpoint_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return text


def _run_options(parser: argparse.ArgumentParser) -> None:
    add = parser.add_argument
    add("--impl", required=True, help="implementations: a module name (pkg.impl) or a .py file")
    add(
        "--rate",
        metavar="HZ",
        type=_number(0, False, "must be 0 or more"),
        default=10.0,
        help="cycles per second for functionalities without :freq (default 10; "
        "0: every functionality in every cycle, no pause)",
    )
    add("--cycles", metavar="N", type=_count, default=0, help="stop after N cycles (0: no limit)")
    add(
        "--duration",
        metavar="S",
        type=_number(0, True, "must be more than 0"),
        default=None,
        help="stop after S seconds (default: until interrupted)",
    )
    add(
        "--stale-periods",
        metavar="K",
        type=_number(0, True, "must be more than 0"),
        default=3.0,
        help="an input not refreshed for K periods of its sender is stale (default 3)",
    )
    add(
        "--budget",
        metavar="S",
        type=_number(0, False, "must be 0 or more"),
        default=DEFAULT_BUDGET,
        help=f"seconds one call may take before it is reported as blocked "
        f"(default {DEFAULT_BUDGET:g}; 0: no budget, calls run on the robot's thread)",
    )
    add("--trace", metavar="FILE", help="write every event to FILE as JSON lines")
    add("--force", action="store_true", help="overwrite the --trace FILE if it exists")
    add("--verbose", action="store_true", help="print every call, not only what actions received")
    add(
        "--inject",
        action="append",
        default=[],
        metavar="FAULT",
        type=_injection,
        help="a scripted fault (repeatable): 'fail compass(Emil) at cycle 20', 'at 2.5s', "
        "'recover compass(Emil) at ...', 'kill Emil at ...'",
    )


def _network_options(parser: argparse.ArgumentParser) -> None:
    add = parser.add_argument
    add(
        "--transport",
        choices=("zenoh", "inprocess"),
        default="zenoh",
        help="zenoh (default): reach the other robots' programs; inprocess: this robot alone",
    )
    add(
        "--society",
        metavar="NAME",
        default=DEFAULT_SOCIETY,
        help=f"keeps societies on one network apart (default {DEFAULT_SOCIETY})",
    )
    add(
        "--listen",
        action="append",
        default=[],
        metavar="ENDPOINT",
        type=_endpoint,
        help="listen on ENDPOINT, e.g. tcp/0.0.0.0:7447 (repeatable)",
    )
    add(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        type=_endpoint,
        help="connect to ENDPOINT, e.g. tcp/192.168.1.7:7447 (repeatable); with --listen or "
        "--connect, multicast scouting is off",
    )
    add("--zenoh-config", metavar="FILE", help="a Zenoh configuration file (JSON5) for the rest")
    add(
        "--lease",
        metavar="S",
        type=_number(0, True, "must be more than 0"),
        default=None,
        help=f"seconds after which a frozen robot is reported lost (default {DEFAULT_LEASE:g})",
    )


def options_of(args: argparse.Namespace) -> RunOptions:
    return RunOptions(
        rate=args.rate,
        cycles=args.cycles,
        duration=args.duration,
        stale_periods=args.stale_periods,
        budget=args.budget or None,
        trace=args.trace,
        force=args.force,
        verbose=args.verbose,
    )


def robot_main(name: str, configure: Configure, argv: Sequence[str] | None = None) -> int:
    """``python emil.py``: run one robot, its global channels over Zenoh."""
    parser = argparse.ArgumentParser(
        description=f"Run {name}'s part of a configuration (cfgplan, thesis 5.2, 5.3)."
    )
    _run_options(parser)
    _network_options(parser)
    args = parser.parse_args(argv)
    transport: Transport | None = None
    trace: TraceFile | None = None
    try:
        registry = Registry.load(args.impl)
        transport = open_transport(name, args.transport, zenoh_options(args))
        robot = Robot(name, registry, transport).configure(configure)
        shared = transport if isinstance(transport, InProcessTransport) else None
        running = Society([robot], shared)
        if args.trace is not None:
            trace = open_trace(args.trace, args.force)
        hooks = _follow(running, args.inject, trace)
        return execute(running, options_of(args), source=registry.source, trace=trace, hooks=hooks)
    except (RunError, KeyboardInterrupt) as exc:
        if transport is not None:
            transport.close()
        if trace is not None:
            trace.close()
        return _failed(exc)


def crash(trace: TraceFile | None) -> None:
    """End this process now, as a crash (a scripted ``kill``), the trace written out."""
    if trace is not None:
        trace.flush()
    os._exit(KILLED)


def _follow(
    running: Society, injections: Sequence[Injection], trace: TraceFile | None
) -> Hooks | None:
    """A robot of its own process on the network follows the coordinator."""
    (robot,) = running.robots
    injector = Injector(injections, running, facts=False, kill=lambda name: crash(trace))
    if not hasattr(robot.transport, "subscribe"):
        return Scripted(injector) if injector.pending else None
    monitor = Monitor()
    monitor.watch(robot)
    member = Member(robot, robot.transport, monitor)  # type: ignore[arg-type]
    return Membership(member, injector)


def zenoh_options(args: argparse.Namespace) -> ZenohOptions:
    return ZenohOptions(
        society=args.society,
        listen=tuple(args.listen),
        connect=tuple(args.connect),
        config_file=args.zenoh_config,
        lease=args.lease,
    )


def open_transport(robot: str, kind: str, options: ZenohOptions) -> Transport:
    """``zenoh``: a session of ``robot``'s own; ``inprocess``: robots of this process only."""
    if kind == "inprocess":
        return InProcessTransport()
    from cfgplan.runtime.zenoh_transport import ZenohTransport

    return ZenohTransport(robot, options)


def society_main(
    programs: Sequence[tuple[str, Configure]], argv: Sequence[str] | None = None
) -> int:
    """``python run_all.py``: run every robot in this process."""
    names = ", ".join(name for name, _ in programs)
    parser = argparse.ArgumentParser(
        description=f"Run {names} in one process (cfgplan, thesis 5.3)."
    )
    _run_options(parser)
    args = parser.parse_args(argv)
    try:
        registry = Registry.load(args.impl)
        running = assemble(programs, registry)
        injector = Injector(args.inject, running)
        hooks = Scripted(injector) if injector.pending else None
        return execute(running, options_of(args), source=registry.source, hooks=hooks)
    except (RunError, KeyboardInterrupt) as exc:
        return _failed(exc)


def _failed(exc: RunError | KeyboardInterrupt) -> int:
    """Exit status 1 for a user error (said compiler style), 130 for Ctrl-C
    before the robots started (once running, Ctrl-C stops them cleanly)."""
    if isinstance(exc, KeyboardInterrupt):
        print("interrupted", file=sys.stderr)
        return 130
    print(exc.render(), file=sys.stderr)
    return 1
