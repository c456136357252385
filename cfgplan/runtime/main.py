"""The command line of emitted programs: ``python emil.py`` and ``python run_all.py``.

A robot's module runs that robot alone (``robot_main``), by default on the
network through Zenoh, so that each robot runs its individual configuration
in its own process, as each ran on its own body in the thesis (5.2.2);
``run_all.py`` runs every robot in one process (``society_main``). Both take
the options of ``cfgplan run``, defined once in :mod:`cfgplan.runtime.options`
(``RUN_OPTIONS``; a robot's module also ``--transport`` and
``NETWORK_OPTIONS``), and like it run until interrupted, ``--cycles`` or
``--duration``.

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
from typing import Any

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.executor import Configure, Robot
from cfgplan.runtime.faults import Injection, misaimed, parse_injection
from cfgplan.runtime.inject import Injector, Scripted
from cfgplan.runtime.launch import Hooks, RunOptions, execute
from cfgplan.runtime.member import Member, Membership
from cfgplan.runtime.monitor import Monitor
from cfgplan.runtime.options import (
    IMPL,
    NETWORK_OPTIONS,
    RESPAWN,
    RUN_OPTIONS,
    SOCIETY,
    UNTIL,
    WITHOUT_COORDINATOR,
    Option,
    choice,
    how_long,
)
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.society import Society, assemble
from cfgplan.runtime.tracefile import TraceFile, open_trace
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.zenoh_config import ZenohOptions
from cfgplan.security.identity import ProblemId
from cfgplan.security.rates import RateLimits

__all__ = ["KILLED", "crash", "robot_main", "society_main"]

KILLED = 137
"""Exit status of a process a scripted ``kill`` ended (as SIGKILL would)."""


def _argparse_type(parse: Callable[[str], object]) -> Callable[[str], object]:
    """An option's parser as argparse calls it: its message, not argparse's."""

    def convert(text: str) -> object:
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return convert


def _add(parser: argparse.ArgumentParser, option: Option[Any], **extra: Any) -> None:
    """Add one of :mod:`cfgplan.runtime.options` to ``parser``."""
    kwargs: dict[str, Any] = {"help": option.help.replace("%", "%%"), **extra}
    if option.metavar is None:
        kwargs["action"] = "store_true"
    else:
        kwargs["metavar"] = option.metavar
        kwargs["default"] = list(option.default) if option.repeat else option.default
        if option.repeat:
            kwargs["action"] = "append"
        if option.parse is not None:
            kwargs["type"] = _argparse_type(option.parse)
    parser.add_argument(option.flag, **kwargs)


TRANSPORT_HELP = "zenoh (default): reach the other robots' programs; inprocess: this robot alone."


def parser_of(description: str, network: bool) -> argparse.ArgumentParser:
    """The command line of an emitted program: every run's options and, for a
    robot's module (``network``), ``--transport`` and the network's."""
    parser = argparse.ArgumentParser(description=f"{description} {UNTIL}")
    for option in RUN_OPTIONS:
        _add(parser, option, **({"required": True} if option is IMPL else {}))
    if network:
        parser.add_argument(
            "--transport",
            metavar="zenoh|inprocess",
            default="zenoh",
            type=_argparse_type(choice(("zenoh", "inprocess"), "a transport")),
            help=TRANSPORT_HELP,
        )
        for option in NETWORK_OPTIONS:
            _add(parser, option)
    return parser


def options_of(args: argparse.Namespace) -> RunOptions:
    return RunOptions(
        rate=args.rate,
        cycles=args.cycles,
        duration=args.duration,
        stale_periods=args.stale_periods,
        budget=args.budget or None,
        max_value_bytes=args.max_value_bytes,
        trace=args.trace,
        trace_max_bytes=args.trace_max_bytes,
        force=args.force,
        verbose=args.verbose,
    )


def robot_main(
    name: str,
    configure: Configure,
    argv: Sequence[str] | None = None,
    *,
    problem: ProblemId | None = None,
) -> int:
    """``python emil.py``: run one robot, its global channels over Zenoh;
    ``problem``, if the program knows it, is announced to the society and
    checked against the others' (:mod:`cfgplan.security.identity`)."""
    description = f"Run {name}'s part of a configuration (cfgplan, thesis 5.2, 5.3)."
    args = parser_of(description, network=True).parse_args(argv)
    transport: Transport | None = None
    trace: TraceFile | None = None
    try:
        registry = Registry.load(args.impl)
        transport = open_transport(name, args.transport, zenoh_options(args, problem))
        robot = Robot(name, registry, transport).configure(configure)
        shared = transport if isinstance(transport, InProcessTransport) else None
        running = Society([robot], shared)
        if args.trace is not None:
            trace = open_trace(args.trace, args.force, max_bytes=args.trace_max_bytes)
        injections = [parse_injection(text) for text in args.inject]
        hooks = _follow(running, injections, trace, args.without_coordinator)
        return execute(
            running,
            options_of(args),
            source=registry.source,
            trace=trace,
            hooks=hooks,
            heading=_heading(name, args),
        )
    except (RunError, KeyboardInterrupt) as exc:
        if transport is not None:
            transport.close()
        if trace is not None:
            trace.close()
        return _failed(exc)


def _heading(names: str, args: argparse.Namespace) -> str:
    """The first line of a run, as ``cfgplan run`` says it: who runs, how long."""
    return f"{names}: running {how_long(args.cycles, args.duration)}"


def crash(trace: TraceFile | None) -> None:
    """End this process now, as a crash (a scripted ``kill``), the trace written out."""
    if trace is not None:
        trace.flush()
    os._exit(KILLED)


def _follow(
    running: Society,
    injections: Sequence[Injection],
    trace: TraceFile | None,
    without: str = WITHOUT_COORDINATOR.default,
) -> Hooks | None:
    """A robot of its own process on the network follows the coordinator."""
    (robot,) = running.robots
    injector = Injector(injections, running, facts=False, kill=lambda name: crash(trace))
    if not hasattr(robot.transport, "subscribe"):
        return Scripted(injector) if injector.pending else None
    monitor = Monitor()
    monitor.watch(robot)
    member = Member(robot, robot.transport, monitor, without=without)  # type: ignore[arg-type]
    return Membership(member, injector)


def zenoh_options(args: argparse.Namespace, problem: ProblemId | None = None) -> ZenohOptions:
    """The network options of an emitted program's command line."""
    return network_options(
        args.society,
        args.listen,
        args.connect,
        args.zenoh_config,
        args.lease,
        args.keys,
        problem=problem,
        allowance=args.rate_allowance,
        router=args.router,
    )


def network_options(
    society: str,
    listen: Sequence[str],
    connect: Sequence[str],
    config_file: str | None,
    lease: float | None,
    keys: str | None,
    *,
    problem: ProblemId | None = None,
    allowance: float | None = None,
    router: Sequence[str] = (),
    plans: bool = False,
) -> ZenohOptions:
    """The Zenoh options of a robot, as ``cfgplan run`` and emitted programs
    take them: with keys and no ``--society``, the keys' society; ``problem``:
    the one it runs, announced to the society (:mod:`cfgplan.security.identity`);
    ``allowance``: ``--rate-allowance`` (:mod:`cfgplan.security.rates`);
    ``router``: ``--router``, the routers it is a client of; ``plans``: it
    runs the problem with the planner (``cfgplan run``, reconfiguring): it
    may take over coordination, and says so."""
    if keys is not None:  # the keys name the society, unless --society does
        from cfgplan.security.zenoh_tls import society_for

        society = society_for(keys, society, SOCIETY.default)
    return ZenohOptions(
        society=society,
        listen=tuple(listen),
        connect=tuple(connect),
        router=tuple(router),
        config_file=config_file,
        lease=lease,
        keys=keys,
        problem=problem,
        rates=RateLimits() if allowance is None else RateLimits(allowance=allowance),
        plans=plans and problem is not None,
    )


def open_transport(robot: str, kind: str, options: ZenohOptions) -> Transport:
    """``zenoh``: a session of ``robot``'s own; ``inprocess``: robots of this
    process only. Without keys, a warning on stderr says the society is open
    to anyone on the network (``cfgplan run`` and emitted programs alike)."""
    if kind == "inprocess":
        return InProcessTransport()
    from cfgplan.runtime.zenoh_transport import ZenohTransport

    if options.keys is None:
        print(
            f"cfgplan: warning: society {options.society} runs without keys: anyone on the "
            "network can read and steer it (cfgplan keys new, then --keys DIR)",
            file=sys.stderr,
        )
    return ZenohTransport(robot, options)


def society_main(
    programs: Sequence[tuple[str, Configure]], argv: Sequence[str] | None = None
) -> int:
    """``python run_all.py``: run every robot in this process."""
    names = ", ".join(name for name, _ in programs)
    description = f"Run {names} in one process (cfgplan, thesis 5.3)."
    parser = parser_of(description, network=False)
    _add(parser, RESPAWN)
    args = parser.parse_args(argv)
    if args.respawn:  # this process supervises one that runs them, started again when it dies
        from cfgplan.runtime.spawn import supervise

        given = sys.argv[1:] if argv is None else argv
        rest = [a for a in given if not (len(a) > 3 and "--respawn".startswith(a))]  # (abbrev.)
        return supervise([sys.executable, sys.argv[0], *rest])
    injections = [parse_injection(text) for text in args.inject]
    for injection in injections:  # every robot is here: one aimed elsewhere is a typo
        wrong = misaimed(injection, [name for name, _ in programs])
        if wrong is not None:
            parser.error(wrong.message + (f" ({wrong.hint})" if wrong.hint else ""))
    try:
        registry = Registry.load(args.impl)
        running = assemble(programs, registry)
        injector = Injector(injections, running)
        hooks = Scripted(injector) if injector.pending else None
        return execute(
            running,
            options_of(args),
            source=registry.source,
            hooks=hooks,
            heading=_heading(names, args),
        )
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
