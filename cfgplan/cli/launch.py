"""``cfgplan launch DOMAIN STATE --impl IMPL``: a whole society in one command.

Every robot and device of the state (with ``--no-reconfigure``: of the
configuration) runs its own ``cfgplan run --robot NAME`` process on this
machine, scouting off: by default each a client of one Zenoh router that
launch starts first (``--topology router``; ``--router`` names one that runs
already; with ``--keys`` the society's secured router, with its own
certificate), or, in a mesh (``--topology mesh``, the default with
``--connect``), each linked to every other, the coordinator (the goal's
robot, 5.5) first, on free loopback ports. Their output is one stream, each
line prefixed with its robot. The logic is :mod:`cfgplan.runtime.spawn`; this
module reads the command line and writes each robot's command. Launch declares
only its own options; those of ``cfgplan run`` are parsed by run's own command
(:class:`LaunchCommand`) and passed on as written. ``--print-commands``
writes, instead, the command each host runs (``--host NAME=ADDRESS``).
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

import difflib
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from cfgplan.cli import registry
from cfgplan.cli.app import usage_error
from cfgplan.cli.options import (
    DomainArg,
    StateArg,
    choice_of,
    choose,
    injections,
    load_problem,
    option,
    parsed,
)
from cfgplan.cli.root import Command, click_command
from cfgplan.cli.run import refuse_combinations
from cfgplan.cli.sequence import first_step
from cfgplan.diagnostics import did_you_mean, run_error
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.options import RESPAWN, endpoint
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


COORDINATOR_ONLY = ("--cycles", "--duration", "--live", "--foxglove")
"""The options of cfgplan run that go to the coordinator alone: its end ends the
run, its page and its Foxglove server show the society."""
ITS_OWN_FILE = ("--trace", "--record")
"""The options of cfgplan run that give each robot its own file (:func:`trace_of`)."""
SET_BY_LAUNCH = {
    "--listen": "launch gives each robot its endpoints (see --topology, --port, --router)",
    "--transport": "each robot runs in a process of its own, over Zenoh",
}
"""The options of cfgplan run that launch sets for each robot itself."""


@dataclass(frozen=True)
class Given:
    """One option of ``cfgplan run`` as written on launch's command line: its
    flag and its words (``--trace run.jsonl``, or ``--trace=run.jsonl``)."""

    flag: str
    words: tuple[str, ...]

    @property
    def value(self) -> str:
        """The value it was given (a flag's: empty)."""
        _, sep, attached = self.words[0].partition("=")
        return attached if sep else " ".join(self.words[1:])


@dataclass(frozen=True)
class RunLine:
    """The options of cfgplan run given to launch, in their order, and what
    run's own command made of them (its parameters, by name)."""

    given: tuple[Given, ...]
    params: Mapping[str, Any]


RUN_LINE = "cfgplan.launch.run"
"""Where :class:`LaunchCommand` leaves the :class:`RunLine` in the context's ``meta``."""


def split(
    args: list[str], own: Sequence[Any], run: Sequence[Any], strict: bool = True
) -> tuple[list[str], list[Given], list[str]]:
    """``args`` parted into launch's own words (its arguments and options, of
    the click parameters ``own``), the options of cfgplan run (of ``run``),
    each with its value, in their order, and, with ``strict``, the options of
    neither; an option of both is launch's."""
    takes: dict[str, tuple[bool, bool]] = {}  # flag -> (launch's, takes a value)
    for params, mine in ((run, False), (own, True)):
        for p in params:
            if p.param_type_name == "option":
                for flag in (*p.opts, *p.secondary_opts):
                    takes[flag] = (mine, not (p.is_flag or p.count))
    words: list[str] = []
    given: list[Given] = []
    unknown: list[str] = []
    i = 0
    while i < len(args):
        word = args[i]
        flag = word.partition("=")[0]
        if word == "--":
            words += args[i:]
            break
        if not word.startswith("-") or word == "-" or (flag not in takes and not strict):
            words.append(word)
            i += 1
            continue
        if flag not in takes:
            unknown.append(word)
            i += 1
            continue
        mine, value = takes[flag]
        n = 2 if value and "=" not in word else 1
        if mine:
            words += args[i : i + n]
        else:
            given.append(Given(flag, tuple(args[i : i + n])))
        i += n
    return words, given, unknown


def _closeness(flag: str, params: Sequence[Any]) -> float:
    """How close ``flag`` is to the nearest option of ``params`` (1: the same)."""
    flags = [f for p in params for f in (*p.opts, *p.secondary_opts) if f.startswith("--")]
    return max((difflib.SequenceMatcher(None, flag, f).ratio() for f in flags), default=0.0)


class LaunchCommand(Command):
    """launch's command line: its own arguments and options, and any option
    of ``cfgplan run``, which goes on to the robots. Run's own command parses
    those, with its own checks and messages, before anything starts: run
    stays the only parser of its options."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        return [*super().collect_usage_pieces(ctx), "--impl IMPL", "[RUN OPTIONS]..."]

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        run = click_command("run")
        strict = not ctx.resilient_parsing
        words, given, unknown = split(args, self.get_params(ctx), run.params, strict)
        try:
            if unknown:  # "No such option", said by the parser with the closest option
                flag = unknown[0].partition("=")[0]
                if _closeness(flag, self.get_params(ctx)) > _closeness(flag, run.params):
                    super().parse_args(ctx, unknown[:1])
                run.make_context("run", unknown[:1])
            for g in given:
                if g.flag in SET_BY_LAUNCH and strict:
                    raise typer.BadParameter(SET_BY_LAUNCH[g.flag], param_hint=f"'{g.flag}'")
            rest: list[str] = super().parse_args(ctx, words)
            if not strict:
                return rest
            line = [str(ctx.params["domain"]), str(ctx.params["state"])]
            parsed_by_run = run.make_context("run", line + [w for g in given for w in g.words])
        except Exception as exc:  # click's usage errors (typer keeps their classes to itself)
            if hasattr(exc, "ctx"):
                exc.ctx = ctx  # run's message under launch's usage line
            raise
        ctx.meta[RUN_LINE] = RunLine(tuple(given), parsed_by_run.params)
        return rest


@registry.command(
    short_help="Start a whole society here, one process per robot (5.2.2).", cls=LaunchCommand
)
def launch(
    ctx: typer.Context,
    domain: DomainArg,
    state: StateArg,
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
    topology: Annotated[
        str | None,
        typer.Option(
            "--topology",
            metavar="router|mesh",
            parser=choice_of(TOPOLOGIES, "a topology"),
            help="router: every robot a client of one Zenoh router (one connection each; "
            "started here, with --keys the society's own, or the one --router names); mesh: "
            "every robot a peer linked to every other (N·(N−1)/2 connections). Default: "
            "router, but mesh with --connect.",
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
            "zenohd, rmw_zenohd; with --keys, cfgplan router --keys), which launch does not "
            "start.",
            show_default=False,
        ),
    ] = None,
    respawn: Annotated[bool, option(RESPAWN)] = RESPAWN.default,
) -> None:
    """Start a whole society on this machine: every robot its own cfgplan run --robot
    process, each a client of one Zenoh router started first (with --keys DIR, the
    society's router with its own certificate: TLS, mutual authentication, the society's
    access control on every robot), or, with --topology mesh, each linked to every other,
    the coordinator first; on loopback with scouting off; each line of output prefixed
    with its robot.

    Give --impl IMPL and any other option of cfgplan run (cfgplan run --help) with
    launch's own: run's command reads them, and a mistake in one is a usage error
    before any robot starts. Each goes unchanged to every robot, except that --cycles, --duration,
    --live and --foxglove go to the coordinator, each --inject to the robot it aims at
    (a change of facts to the coordinator), --trace FILE and --record FILE to every
    robot as FILE-NAME. Launch adds each robot's --robot and its endpoints (--listen and
    --connect, or --router); --listen and --transport are its own business.

    Ctrl-C or SIGTERM stops every robot (SIGTERM, at most 10 s, then SIGKILL). When the
    coordinator ends (--cycles, --duration, the task done), the others are stopped.
    --print-commands starts nothing and prints the command of each robot's host
    instead (--host NAME=ADDRESS for each). Exit codes: the coordinator's (0 ran, 3 no
    configuration left), 1 invalid input or a robot that could not start or run its
    part, 2 usage.
    """
    line: RunLine = ctx.meta[RUN_LINE]
    run_opts = line.params  # as run's command read them
    refuse_combinations(
        "zenoh",
        keys=run_opts["keys"],
        ros2=run_opts["ros2"],
        ros2_map=run_opts["ros2_map"],
        ros_domain_id=run_opts["ros_domain_id"],
        ros2_via=run_opts["ros2_via"],
        use_sim_time=run_opts["use_sim_time"],
    )
    if hosts and not print_commands:
        usage_error("names the hosts of --print-commands: give --print-commands", "--host")
    mesh = _mesh(topology, router, run_opts["connect"])
    addresses = dict(_parse_hosts(hosts or ()))
    problem = load_problem(
        domain, state, run_opts["goal"], run_opts["weights"], sequence=True, lasting=True
    )
    rank = run_opts["rank"]
    config = first_step(problem, rank) if len(problem.goals) > 1 else choose(problem, rank)
    from cfgplan.reconfigure.owner import coordinator_of

    lead = coordinator_of(problem.goal_call, config)
    known = list(problem.task.agents) if run_opts["reconfigure"] else list(config.agents)
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
    if run_opts["ros2_map"] is not None:  # its mistakes said once, before any robot starts
        from cfgplan.ros2.topics import load_map

        try:
            load_map(run_opts["ros2_map"], problem.domain, problem.task.agents)
        except RunError as exc:
            raise run_error(exc) from None
    robots = [lead, *(r for r in known if r != lead)]
    if only:
        robots = [r for r in robots if r in only]
    common = ["run", str(domain), str(state)]
    extra: dict[str, list[str]] = {r: [] for r in robots}
    aimed = iter(injections(run_opts["inject"], problem))
    for one in line.given:
        if one.flag in COORDINATOR_ONLY:
            if lead not in extra:
                usage_error(f"goes to the coordinator, {lead}, which --robot leaves out", one.flag)
            extra[lead] += one.words
        elif one.flag == "--inject":
            target = next(aimed).robot or lead  # a state update: the coordinator plans
            if target not in extra:
                usage_error(f"aims at {target}, which --robot leaves out", "--inject")
            extra[target] += one.words
        elif one.flag in ITS_OWN_FILE:
            for r in robots:
                extra[r] += [one.flag, trace_of(one.value, r)]
        else:
            common += one.words
    keys = next((g.value for g in line.given if g.flag == "--keys"), None)
    via = None if mesh else Via(router, run_opts["lease"], keys)
    if via is not None and via.given is None and keys is not None:
        from cfgplan.security.zenoh_tls import router_of

        try:  # its mistakes said before any robot starts
            router_of(run_opts["keys"])
        except RunError as exc:
            raise run_error(exc) from None
    if print_commands:
        _print_commands(robots, lead, common, extra, addresses, port, via)
        return
    config_file = run_opts["zenoh_config"]
    _launch(robots, lead, common, extra, port, config_file, SpawnOptions(respawn=respawn), via)


@dataclass(frozen=True)
class Via:
    """The robots are clients of a router: ``given``, one that runs already
    (``--router``), or one launch starts (``None``), with the robots' lease and,
    as written, their ``--keys`` folder (the router's certificate is in it)."""

    given: str | None
    lease: float | None
    keys: str | None = None

    def started(self, host: str, port: int, listen: str) -> RobotCommand | None:
        """The router's command, when launch starts it (listening on ``listen``:``port``,
        reached at ``host``:``port``)."""
        if self.given is not None:
            return None
        return router_command(host, port, self._at(listen, port), self.lease, self.keys)

    def endpoint(self, host: str, port: int) -> str:
        """What the robots connect to."""
        return self.given if self.given is not None else self._at(host, port)

    def _at(self, host: str, port: int) -> str:
        """An endpoint of the router's: with keys, TLS."""
        at = endpoint_of(host, port)
        return at if self.keys is None else f"tls/{at.removeprefix('tcp/')}"


def _mesh(topology: str | None, router: str | None, connect: list[str] | None) -> bool:
    """Whether the robots are a mesh of peers (``--topology``, and its default)."""
    if router is not None and topology == "mesh":
        usage_error("names a router: not with --topology mesh", "--router")
    if topology == "router" or router is not None:
        if connect:
            usage_error(
                "cannot be combined with --connect: a client of a router reaches the others "
                "only through it",
                "--router" if router is not None else "--topology",
            )
        return False
    return topology == "mesh" or bool(connect)


def _parse_hosts(texts: list[str] | tuple[str, ...]) -> list[tuple[str, str]]:
    try:
        return [_host(t) for t in texts]
    except ValueError as exc:
        usage_error(str(exc), "--host")


def _print_commands(
    robots: list[str],
    lead: str,
    common: list[str],
    extra: dict[str, list[str]],
    addresses: dict[str, str],
    port: int | None,
    via: Via | None,
) -> None:
    missing = [r for r in robots if r not in addresses]
    if missing:
        usage_error(f"give the host of {', '.join(missing)} (NAME=ADDRESS)", "--host")
    ports: dict[str, int] = {}
    base = port or DEFAULT_PORT
    for r in robots:  # a second robot on a host takes the next port
        ports[r] = base + sum(1 for o in ports if addresses[o] == addresses[r])
    reach = None
    if via is not None:  # the router on the coordinator's host, unless one is named
        if via.given is None and lead not in addresses:
            usage_error(
                f"give --router ENDPOINT (the society's router), or the host of {lead}, the "
                "coordinator, whose host runs the router (NAME=ADDRESS)",
                "--host",
            )
        host, at = addresses.get(lead, ""), port or DEFAULT_PORT
        router = via.started(host, at, "0.0.0.0")
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
        router = via.started(host, at, host)
        started += [router] if router is not None else []
        reach = via.endpoint(host, at)
    with tempfile.TemporaryDirectory(prefix="cfgplan-launch-") as folder:
        if zenoh_config is None:  # else it is among the options of run given
            hermetic = Path(folder) / "zenoh-hermetic.json5"
            hermetic.write_text(HERMETIC, "utf-8")
            common = [*common, "--zenoh-config", str(hermetic)]
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
