"""``cfgplan launch DOMAIN STATE --impl IMPL``: a whole society in one command.

Every robot and device of the state (with ``--no-reconfigure``: of the
configuration) runs its own ``cfgplan run --robot NAME`` process on this
machine, scouting off: by default each a client of one Zenoh router that
launch starts first (``--topology router``; ``--router`` names one that runs
already), or, in a mesh (``--topology mesh``, the default with ``--keys`` or
``--connect``), each linked to every other, the coordinator (the goal's
robot, 5.5) first, on free loopback ports. Their output is one stream, each
line prefixed with its robot. The logic is :mod:`cfgplan.runtime.spawn`; this module reads the
command line and writes each robot's command. ``--print-commands`` writes,
instead, the command each host runs (``--host NAME=ADDRESS``).
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from cfgplan.cli import registry
from cfgplan.cli.app import usage_error
from cfgplan.cli.options import (
    DomainArg,
    GoalsOpt,
    RankOpt,
    StateArg,
    choice_of,
    choose,
    injections,
    load_problem,
    number_of,
    option,
    parsed,
)
from cfgplan.cli.sequence import first_step
from cfgplan.configuration.cost import parse_weights
from cfgplan.diagnostics import did_you_mean, run_error
from cfgplan.live.address import parse_address
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.options import (
    BUDGET,
    CYCLES,
    DURATION,
    FORCE,
    IMPL,
    INJECT,
    KEYS,
    LEASE,
    MAX_VALUE_BYTES,
    RATE,
    RATE_ALLOWANCE,
    RECORD,
    RECORD_MAX_BYTES,
    RESPAWN,
    SOCIETY,
    STALE_PERIODS,
    TRACE,
    TRACE_MAX_BYTES,
    VERBOSE,
    WITHOUT_COORDINATOR,
    ZENOH_CONFIG,
    endpoint,
)
from cfgplan.runtime.spawn import (
    Launch,
    RobotCommand,
    SpawnOptions,
    commands,
    free_port,
    router_command,
)
from cfgplan.runtime.spawn import endpoint as endpoint_of

HERMETIC = (
    "{ // cfgplan launch: robots meet only through the endpoints given, and what they\n"
    "  // learn over them: gossip on, as cfgplan run's, so that behind a --connect\n"
    "  // router (rmw_zenohd) its ROS 2 peers and the robots find each other\n"
    "  scouting: { multicast: { enabled: false }, gossip: { enabled: true } },\n}\n"
)
"""The Zenoh configuration of the launched robots when no --zenoh-config is given:
no multicast scouting (nothing off this host is found), gossip as Zenoh's default
(it spreads only the locators of sessions already connected: the robots' own
loopback endpoints, and what a --connect router knows)."""
TOPOLOGIES = ("router", "mesh")
"""How the launched robots reach each other: through one router, or each to every other."""
DEFAULT_PORT = 7447
"""Zenoh's port: each robot's with --print-commands, the next for a second robot on a host."""


def _weights(text: str) -> str:
    parse_weights(text)  # its error, said as --weights's
    return text


def _address(text: str) -> str:
    parse_address(text)  # its error, said as the option's
    return text


def _host(text: str) -> tuple[str, str]:
    name, sep, address = text.partition("=")
    if not sep or not name or not address:
        raise ValueError(f"{text!r} is not NAME=ADDRESS (e.g. Emil=192.168.1.7)")
    return name, address


def trace_of(path: str, robot: str) -> str:
    """Robot ``robot``'s trace: ``{robot}`` in ``path`` replaced by its name in
    lower case, else the name before the suffix (``run.jsonl`` -> ``run-emil.jsonl``)."""
    name = robot.lower()
    if "{robot}" in path:
        return path.replace("{robot}", name)
    p = Path(path)
    return str(p.with_name(f"{p.stem}-{name}{p.suffix}"))


@registry.command(short_help="Start a whole society here, one process per robot (5.2.2).")
def launch(
    domain: DomainArg,
    state: StateArg,
    impl: Annotated[str, option(IMPL)],
    goal: GoalsOpt = None,
    rank: RankOpt = 1,
    weights: Annotated[
        str | None,
        typer.Option(
            "--weights", metavar="NAME=W,...", parser=parsed(_weights), help="As cfgplan run's."
        ),
    ] = None,
    only: Annotated[
        list[str] | None,
        typer.Option(
            "--robot",
            metavar="NAME",
            help="Start only this robot (repeatable; default: every robot and device of the "
            "state, or with --no-reconfigure of the configuration).",
        ),
    ] = None,
    port: Annotated[
        int | None,
        typer.Option(
            "--port",
            metavar="N",
            min=1,
            max=65535,
            help="The router's port, in a mesh the coordinator's (default: a free one; with "
            f"--print-commands {DEFAULT_PORT}, and in a mesh the next ones for more robots on a "
            "host).",
            show_default=False,
        ),
    ] = None,
    print_commands: Annotated[
        bool,
        typer.Option(
            "--print-commands",
            help="Start nothing: print the command each robot's host runs (give --host for "
            "every robot).",
        ),
    ] = False,
    hosts: Annotated[
        list[str] | None,
        typer.Option(
            "--host",
            metavar="NAME=ADDRESS",
            help="With --print-commands: the address robot NAME's host is reached at (repeatable).",
        ),
    ] = None,
    society_name: Annotated[str, option(SOCIETY)] = SOCIETY.default,
    topology: Annotated[
        str | None,
        typer.Option(
            "--topology",
            metavar="router|mesh",
            parser=choice_of(TOPOLOGIES, "a topology"),
            help="router: every robot a client of one Zenoh router (one connection each; "
            "started here, or the one --router names); mesh: every robot a peer linked to "
            "every other (N·(N−1)/2 connections). Default: router, but mesh with --keys or "
            "--connect (a router is not one of the society's keys).",
            show_default=False,
        ),
    ] = None,
    router: Annotated[
        str | None,
        typer.Option(
            "--router",
            metavar="ENDPOINT",
            parser=parsed(endpoint),
            help="The robots are clients of the Zenoh router at ENDPOINT (cfgplan router, "
            "zenohd, rmw_zenohd), which launch does not start.",
            show_default=False,
        ),
    ] = None,
    connect: Annotated[
        list[str] | None,
        typer.Option(
            "--connect",
            metavar="ENDPOINT",
            parser=parsed(endpoint),
            help="Also connect every robot to ENDPOINT, e.g. an rmw_zenohd router at "
            "tcp/localhost:7447 (repeatable).",
        ),
    ] = None,
    zenoh_config: Annotated[Path | None, option(ZENOH_CONFIG)] = None,
    lease: Annotated[float | None, option(LEASE)] = LEASE.default,
    keys: Annotated[Path | None, option(KEYS)] = None,
    rate: Annotated[float, option(RATE)] = RATE.default,
    rate_allowance: Annotated[float, option(RATE_ALLOWANCE)] = RATE_ALLOWANCE.default,
    cycles: Annotated[int, option(CYCLES)] = CYCLES.default,
    duration: Annotated[float | None, option(DURATION)] = DURATION.default,
    stale_periods: Annotated[float, option(STALE_PERIODS)] = STALE_PERIODS.default,
    budget: Annotated[float, option(BUDGET)] = BUDGET.default,
    max_value_bytes: Annotated[int, option(MAX_VALUE_BYTES)] = MAX_VALUE_BYTES.default,
    trace: Annotated[Path | None, option(TRACE)] = None,
    trace_max_bytes: Annotated[int, option(TRACE_MAX_BYTES)] = TRACE_MAX_BYTES.default,
    record: Annotated[Path | None, option(RECORD)] = None,
    record_max_bytes: Annotated[int, option(RECORD_MAX_BYTES)] = RECORD_MAX_BYTES.default,
    live: Annotated[
        str | None,
        typer.Option(
            "--live",
            metavar="[HOST:]PORT",
            parser=parsed(_address),
            help="The coordinator's live page, as cfgplan run's (port 0: any free one, its URL "
            "printed).",
            show_default=False,
        ),
    ] = None,
    foxglove: Annotated[
        str | None,
        typer.Option(
            "--foxglove",
            metavar="[HOST:]PORT",
            parser=parsed(_address),
            help="The coordinator served to Foxglove live, as cfgplan run's.",
            show_default=False,
        ),
    ] = None,
    force: Annotated[bool, option(FORCE)] = FORCE.default,
    verbose: Annotated[bool, option(VERBOSE)] = VERBOSE.default,
    inject: Annotated[list[str] | None, option(INJECT)] = None,
    ros2: Annotated[
        bool, typer.Option("--ros2", help="Every robot a ROS 2 node (as cfgplan run --ros2).")
    ] = False,
    ros2_map: Annotated[
        Path | None,
        typer.Option("--ros2-map", metavar="FILE", help="As cfgplan run's: given to every robot."),
    ] = None,
    ros_domain_id: Annotated[
        int | None,
        typer.Option(
            "--ros-domain-id",
            metavar="N",
            min=0,
            max=232,
            help="As cfgplan run's.",
            show_default=False,
        ),
    ] = None,
    reconfigure: Annotated[
        bool, typer.Option("--reconfigure/--no-reconfigure", help="As cfgplan run's.")
    ] = True,
    hold: Annotated[
        float | None,
        typer.Option(
            "--hold", metavar="S", parser=number_of(0, above=True), help="As cfgplan run's."
        ),
    ] = None,
    margin: Annotated[
        float | None,
        typer.Option("--margin", metavar="F", parser=number_of(0), help="As cfgplan run's."),
    ] = None,
    without_coordinator: Annotated[str, option(WITHOUT_COORDINATOR)] = WITHOUT_COORDINATOR.default,
    respawn: Annotated[bool, option(RESPAWN)] = RESPAWN.default,
) -> None:
    """Start a whole society on this machine: every robot its own cfgplan run --robot
    process, each a client of one Zenoh router started first (or, with --topology mesh,
    each linked to every other, the coordinator first), on loopback with scouting off;
    each line of output prefixed with its robot.

    Ctrl-C or SIGTERM stops every robot (SIGTERM, at most 10 s, then SIGKILL). When the
    coordinator ends (--cycles, --duration, the task done), the others are stopped.
    --cycles, --duration, --live and --foxglove go to the coordinator, each --inject to
    the robot it aims at (a change of facts to the coordinator), --trace FILE and
    --record FILE to every robot as FILE-NAME.
    --print-commands starts nothing and prints the command of each robot's host
    instead (--host NAME=ADDRESS for each). Exit codes: the coordinator's (0 ran, 3 no
    configuration left), 1 invalid input or a robot that could not start or run its
    part, 2 usage.
    """
    if ros2 and keys is not None:
        usage_error("cannot be combined with --keys yet (docs: Use cfgplan with ROS 2)", "--ros2")
    if ros2_map is not None and keys is not None:
        usage_error(
            "cannot be combined with --keys yet (docs: Use cfgplan with ROS 2)", "--ros2-map"
        )
    if ros_domain_id is not None and not (ros2 or ros2_map):
        usage_error("is the ROS domain of --ros2: give --ros2", "--ros-domain-id")
    if hosts and not print_commands:
        usage_error("names the hosts of --print-commands: give --print-commands", "--host")
    mesh = _mesh(topology, router, keys, connect)
    addresses = dict(_parse_hosts(hosts or ()))
    problem = load_problem(
        domain,
        state,
        goal,
        None if weights is None else parse_weights(weights),
        sequence=True,
        lasting=True,
    )
    config = first_step(problem, rank) if len(problem.goals) > 1 else choose(problem, rank)
    from cfgplan.reconfigure.local import coordinator_of

    lead = coordinator_of(problem.goal_call, config)
    known = list(problem.task.agents) if reconfigure else list(config.agents)
    for name in [*(only or ()), *addresses]:
        if name not in problem.task.agents:
            raise run_error(
                RunError(
                    f"no robot {name} in {state} (its robots: {', '.join(known)})",
                    hint=did_you_mean(name, problem.task.agents),
                )
            )
        if name not in known:
            raise run_error(
                RunError(f"{name} has no part in this configuration (--no-reconfigure)")
            )
    if ros2_map is not None:  # its mistakes said once, before any robot starts
        from cfgplan.ros2.topics import load_map

        try:
            load_map(ros2_map, problem.domain, problem.task.agents)
        except RunError as exc:
            raise run_error(exc) from None
    robots = [lead, *(r for r in known if r != lead)]
    if only:
        robots = [r for r in robots if r in only]
    common = ["run", str(domain), str(state), "--impl", impl]
    for g in goal or ():
        common += ["--goal", g]
    common += _flags(
        rank=(rank, 1), weights=(weights, None), society=(society_name, SOCIETY.default),
        lease=(lease, None), keys=(keys, None), rate=(rate, RATE.default),
        rate_allowance=(rate_allowance, RATE_ALLOWANCE.default),
        record_max_bytes=(record_max_bytes, RECORD_MAX_BYTES.default),
        stale_periods=(stale_periods, STALE_PERIODS.default), budget=(budget, BUDGET.default),
        max_value_bytes=(max_value_bytes, MAX_VALUE_BYTES.default),
        trace_max_bytes=(trace_max_bytes, TRACE_MAX_BYTES.default), hold=(hold, None),
        margin=(margin, None), ros_domain_id=(ros_domain_id, None), ros2_map=(ros2_map, None),
        without_coordinator=(without_coordinator, WITHOUT_COORDINATOR.default),
    )  # fmt: skip
    for e in connect or ():
        common += ["--connect", e]
    common += [f for f, on in (("--force", force), ("--verbose", verbose), ("--ros2", ros2)) if on]
    if not reconfigure:
        common.append("--no-reconfigure")
    extra: dict[str, list[str]] = {r: [] for r in robots}
    led = _flags(
        cycles=(cycles, 0), duration=(duration, None), live=(live, None), foxglove=(foxglove, None)
    )
    if led and lead not in extra:
        usage_error(f"goes to the coordinator, {lead}, which --robot leaves out", led[0])
    if led:
        extra[lead] += led
    for text, injection in zip(inject or (), injections(inject, problem), strict=True):
        target = injection.robot or lead  # a state update: the coordinator plans
        if target not in extra:
            usage_error(f"aims at {target}, which --robot leaves out", "--inject")
        extra[target] += ["--inject", text]
    for flag, path in (("--trace", trace), ("--record", record)):
        if path is not None:
            for r in robots:
                extra[r] += [flag, trace_of(str(path), r)]
    via = None if mesh else Via(router, lease)
    if print_commands:
        _print_commands(robots, lead, common, extra, addresses, port, zenoh_config, via)
        return
    _launch(robots, lead, common, extra, port, zenoh_config, SpawnOptions(respawn=respawn), via)


@dataclass(frozen=True)
class Via:
    """The robots are clients of a router: ``given``, one that runs already
    (``--router``), or one launch starts (``None``), with the robots' lease."""

    given: str | None
    lease: float | None

    def started(self, host: str, port: int, listen: str) -> RobotCommand | None:
        """The router's command, when launch starts it (listening on ``listen``,
        reached at ``host``:``port``)."""
        return None if self.given is not None else router_command(host, port, listen, self.lease)

    def endpoint(self, host: str, port: int) -> str:
        """What the robots connect to."""
        return self.given if self.given is not None else endpoint_of(host, port)


def _mesh(
    topology: str | None, router: str | None, keys: Path | None, connect: list[str] | None
) -> bool:
    """Whether the robots are a mesh of peers (``--topology``, and its default)."""
    if router is not None and topology == "mesh":
        usage_error("names a router: not with --topology mesh", "--router")
    if topology == "router" or router is not None:
        if keys is not None:
            usage_error(
                "cannot be combined with --keys: the society's keys name its robots, not a "
                "router (use --topology mesh)",
                "--router" if router is not None else "--topology",
            )
        if connect:
            usage_error(
                "cannot be combined with --connect: a client of a router reaches the others "
                "only through it",
                "--router" if router is not None else "--topology",
            )
        return False
    return topology == "mesh" or keys is not None or bool(connect)


def _parse_hosts(texts: list[str] | tuple[str, ...]) -> list[tuple[str, str]]:
    try:
        return [_host(t) for t in texts]
    except ValueError as exc:
        usage_error(str(exc), "--host")


def _flags(**given: tuple[Any, Any]) -> list[str]:
    """``--name value`` for each option given a value other than its default."""
    out: list[str] = []
    for name, (value, default) in given.items():
        if value is not None and value != default:
            text = str(value)  # a float exactly as given (repr), without a trailing .0
            if isinstance(value, float) and text.endswith(".0"):
                text = text[:-2]
            out += [f"--{name.replace('_', '-')}", text]
    return out


def _print_commands(
    robots: list[str],
    lead: str,
    common: list[str],
    extra: dict[str, list[str]],
    addresses: dict[str, str],
    port: int | None,
    zenoh_config: Path | None,
    via: Via | None,
) -> None:
    missing = [r for r in robots if r not in addresses]
    if missing:
        usage_error(f"give the host of {', '.join(missing)} (NAME=ADDRESS)", "--host")
    ports: dict[str, int] = {}
    base = port or DEFAULT_PORT
    for r in robots:  # a second robot on a host takes the next port
        ports[r] = base + sum(1 for o in ports if addresses[o] == addresses[r])
    if zenoh_config is not None:
        common = [*common, "--zenoh-config", str(zenoh_config)]
    reach = None
    if via is not None:  # the router on the coordinator's host, unless one is named
        if via.given is None and lead not in addresses:
            usage_error(
                f"give --router ENDPOINT (the society's router), or the host of {lead}, the "
                "coordinator, whose host runs the router (NAME=ADDRESS)",
                "--host",
            )
        host, at = addresses.get(lead, ""), port or DEFAULT_PORT
        router = via.started(host, at, endpoint_of("0.0.0.0", at))
        if router is not None:
            typer.echo(f"# the router on {host} (start it first)")
            typer.echo(router.shell())
        reach = via.endpoint(host, at)
    for command in commands(robots, common, extra, addresses, ports, lead, reach):
        role = " (coordinator: start it first)" if command.robot == lead else ""
        if via is not None:
            role = " (coordinator)" if command.robot == lead else ""
        typer.echo(f"# {command.robot} on {command.host}{role}")
        typer.echo(command.shell())


def _launch(
    robots: list[str],
    lead: str,
    common: list[str],
    extra: dict[str, list[str]],
    port: int | None,
    zenoh_config: Path | None,
    options: SpawnOptions | None = None,
    via: Via | None = None,
) -> None:
    host = "127.0.0.1"
    ports = {r: free_port(host) for r in robots} if via is None else {}
    if port is not None:
        ports[lead] = port
    started: list[RobotCommand] = []
    reach = None
    if via is not None:  # one port: the router's (--port), a free one else
        at = port if port is not None else free_port(host)
        router = via.started(host, at, endpoint_of(host, at))
        started += [router] if router is not None else []
        reach = via.endpoint(host, at)
    with tempfile.TemporaryDirectory(prefix="cfgplan-launch-") as folder:
        if zenoh_config is None:
            hermetic = Path(folder) / "zenoh-hermetic.json5"
            hermetic.write_text(HERMETIC, "utf-8")
            zenoh_config = hermetic
        common = [*common, "--zenoh-config", str(zenoh_config)]
        hosts = dict.fromkeys(robots, host)
        started += commands(robots, common, extra, hosts, ports, lead, reach)
        launched = Launch(started, options=options)
        try:
            code = launched.run()
        except RunError as exc:
            sys.stdout.flush()
            raise run_error(exc) from None
    if code:
        raise typer.Exit(code)
