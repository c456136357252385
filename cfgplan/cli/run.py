"""``cfgplan run DOMAIN STATE --impl IMPL``: execute a configuration (chapter 5).

The configuration of the given rank is sorted, divided and wired as for
``cfgplan emit``, then run: every robot in this process (global channels
joined by the in-process transport), or with ``--robot NAME`` that robot's
part alone, its global channels over Zenoh to the other robots' programs
(``cfgplan run --robot`` or the emitted ``emil.py``, on this host or others).
With ``--robot``, a robot that never coordinates
(:func:`~cfgplan.reconfigure.owner.never_coordinates`) plans nothing: it runs
the part its coordinator sends it, unless its implementations cannot take
every functionality of the domain (its part is then checked at start) or an
option shows the configuration (``--ros2``, ``--ros2-map``, ``--live``,
``--foxglove``).
The options are those of the emitted programs (:mod:`cfgplan.runtime.main`);
the console (:mod:`cfgplan.runtime.console`) shows a compact status (in
place on a terminal, a plain line every 100 cycles otherwise), every loss,
stale input, failure and switch with its cause, what an action receives when
it starts to (``--verbose``: every call, each cycle), then per functionality
how often it ran. ``--cycles N`` counts the cycles of the goal's robot
(:func:`~cfgplan.reconfigure.local.coordinator_of`), whatever robots a
switch brings in.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from cfgplan.cli.app import usage_error
from cfgplan.cli.options import (
    DomainArg,
    GoalsOpt,
    RankOpt,
    StateArg,
    WeightsOpt,
    choice_of,
    choose,
    completing,
    injections,
    load_problem,
    number_of,
    option,
    parsed,
)
from cfgplan.cli.registry import command
from cfgplan.diagnostics import did_you_mean, run_error
from cfgplan.live.address import Address, parse_address
from cfgplan.notation import call_text
from cfgplan.reconfigure.owner import coordinator_of, never_coordinates
from cfgplan.reconfigure.setup import Settings, hooks
from cfgplan.runtime import Registry, RunError, RunOptions, Society, build, execute, society
from cfgplan.runtime.main import network_options, open_transport
from cfgplan.runtime.monitor import HOLD
from cfgplan.runtime.options import (
    BUDGET,
    CONNECT,
    CYCLES,
    DURATION,
    FORCE,
    IMPL,
    INJECT,
    KEYS,
    LEASE,
    LISTEN,
    MAX_VALUE_BYTES,
    RATE,
    RATE_ALLOWANCE,
    RECORD,
    RECORD_MAX_BYTES,
    ROUTER,
    SOCIETY,
    STALE_PERIODS,
    TRACE,
    TRACE_MAX_BYTES,
    VERBOSE,
    WITHOUT_COORDINATOR,
    ZENOH_CONFIG,
    how_long,
)
from cfgplan.runtime.part import Part
from cfgplan.runtime.tracefile import TraceFile, open_trace
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.security.identity import problem_id

if TYPE_CHECKING:
    from cfgplan.configuration.model import Configuration
    from cfgplan.problem import Problem
    from cfgplan.ros2.bindings import Bindings

TRANSPORTS = ("zenoh", "inprocess")


@command(short_help="Run a configuration: all robots here, or one on the network (5.2).")
def run(
    domain: DomainArg,
    state: StateArg,
    impl: Annotated[str, option(IMPL)],
    goal: GoalsOpt = None,
    rank: RankOpt = 1,
    weights: WeightsOpt = None,
    robot: Annotated[
        str | None,
        typer.Option(
            "--robot", metavar="NAME", help="Run only this robot's part (default: every robot)."
        ),
    ] = None,
    transport: Annotated[
        str | None,
        typer.Option(
            "--transport",
            metavar="|".join(TRANSPORTS),
            parser=choice_of(TRANSPORTS, "a transport"),
            autocompletion=completing(TRANSPORTS),
            help="zenoh: reach the other robots' programs (the default with --robot); "
            "inprocess: robots of this process only (the default without --robot).",
        ),
    ] = None,
    society_name: Annotated[str, option(SOCIETY)] = SOCIETY.default,
    listen: Annotated[list[str] | None, option(LISTEN)] = None,
    connect: Annotated[list[str] | None, option(CONNECT)] = None,
    router: Annotated[list[str] | None, option(ROUTER)] = None,
    zenoh_config: Annotated[Path | None, option(ZENOH_CONFIG)] = None,
    lease: Annotated[float | None, option(LEASE)] = LEASE.default,
    keys: Annotated[Path | None, option(KEYS)] = None,
    rate_allowance: Annotated[float, option(RATE_ALLOWANCE)] = RATE_ALLOWANCE.default,
    without_coordinator: Annotated[str, option(WITHOUT_COORDINATOR)] = WITHOUT_COORDINATOR.default,
    rate: Annotated[float, option(RATE)] = RATE.default,
    cycles: Annotated[int, option(CYCLES)] = CYCLES.default,
    duration: Annotated[float | None, option(DURATION)] = DURATION.default,
    stale_periods: Annotated[float, option(STALE_PERIODS)] = STALE_PERIODS.default,
    budget: Annotated[float, option(BUDGET)] = BUDGET.default,
    max_value_bytes: Annotated[int, option(MAX_VALUE_BYTES)] = MAX_VALUE_BYTES.default,
    trace: Annotated[Path | None, option(TRACE)] = None,
    trace_max_bytes: Annotated[int, option(TRACE_MAX_BYTES)] = TRACE_MAX_BYTES.default,
    record: Annotated[Path | None, option(RECORD)] = None,
    record_max_bytes: Annotated[int, option(RECORD_MAX_BYTES)] = RECORD_MAX_BYTES.default,
    force: Annotated[bool, option(FORCE)] = FORCE.default,
    verbose: Annotated[bool, option(VERBOSE)] = VERBOSE.default,
    inject: Annotated[list[str] | None, option(INJECT)] = None,
    ros2: Annotated[
        bool,
        typer.Option(
            "--ros2",
            help="Make the robot a ROS 2 node (see --ros2-via) and publish its switches, "
            "failures and recoveries on /cfgplan/events, and each global channel it sends on "
            "/cfgplan/channel/... (needs --robot; pip install 'cfgplan[ros2]').",
        ),
    ] = False,
    ros2_map: Annotated[
        Path | None,
        typer.Option(
            "--ros2-map",
            metavar="FILE",
            help="Bind functionality inputs and outputs to ROS 2 topics, as the TOML FILE's "
            "[[bind]] tables say (needs --robot; docs: Use cfgplan with ROS 2).",
        ),
    ] = None,
    ros2_via: Annotated[
        str | None,
        typer.Option(
            "--ros2-via",
            metavar="rclpy|zenoh",
            help="How --ros2 and --ros2-map speak ROS 2: rclpy, a real node on your ROS 2's "
            "middleware (DDS by default, RMW_IMPLEMENTATION honoured), or zenoh, rmw_zenoh's "
            "layout over the robot's own Zenoh session (default: CFGPLAN_ROS2_VIA if set, else "
            "rclpy where it can be imported, else zenoh).",
            show_default=False,
        ),
    ] = None,
    use_sim_time: Annotated[
        bool,
        typer.Option(
            "--use-sim-time",
            help="The rclpy node's use_sim_time parameter: headers are stamped with /clock.",
        ),
    ] = False,
    ros_domain_id: Annotated[
        int | None,
        typer.Option(
            "--ros-domain-id",
            metavar="N",
            min=0,
            max=232,
            help="The ROS domain of --ros2 (default: ROS_DOMAIN_ID if set, else 0).",
            show_default=False,
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
            metavar="S",
            parser=number_of(0, above=True),
            help="Seconds a failed resource must work again before it counts as recovered "
            f"(doubled at each further failure; default {HOLD:g}).",
            show_default=False,
        ),
    ] = HOLD,
    live: Annotated[
        Address | None,
        typer.Option(
            "--live",
            metavar="[HOST:]PORT",
            parser=parsed(parse_address),
            help="Serve a live page of the run: the configuration, freshness, switches, "
            "fallbacks (port 0: any free one, its URL printed). HOST defaults to 127.0.0.1, "
            "this machine only: the page has no login; give 0.0.0.0:PORT to open it to the "
            "network (pip install 'cfgplan[live]').",
            show_default=False,
        ),
    ] = None,
    foxglove: Annotated[
        Address | None,
        typer.Option(
            "--foxglove",
            metavar="[HOST:]PORT",
            parser=parsed(parse_address),
            help="Serve the run to Foxglove live (its WebSocket protocol: connect to "
            "ws://HOST:PORT): the configuration as a topic graph, events, switches and "
            "freshness on JSON channels. HOST defaults to 127.0.0.1 (port 0: any free one); "
            "pip install 'cfgplan[foxglove]'.",
            show_default=False,
        ),
    ] = None,
    margin: Annotated[
        float,
        typer.Option(
            "--margin",
            metavar="F",
            parser=number_of(0),
            help="A running configuration is left for a cheaper one only when the cost falls "
            "by this share of it (and by 1 at least; default 0.1).",
            show_default=False,
        ),
    ] = 0.1,
) -> None:
    """Execute a configuration: every robot in this process, or one robot on the network
    (thesis 5.2, 5.3).

    Runs until interrupted (Ctrl-C or SIGTERM), or for --cycles or --duration,
    or until the action's task is accomplished. Watches the run and switches to
    another configuration when a resource fails (5.5), unless --no-reconfigure.
    Exit codes: 0 ran, 1 invalid input or a failing implementation, 2 usage, 3 no
    configuration of that rank, or none left at the end of the run.
    """
    kind = transport or ("zenoh" if robot is not None else "inprocess")
    if robot is None and kind == "zenoh":
        usage_error("runs one robot per process: give --robot NAME", "--transport zenoh")
    refuse_combinations(
        kind,
        keys=keys,
        ros2=ros2,
        ros2_map=ros2_map,
        ros_domain_id=ros_domain_id,
        ros2_via=ros2_via,
        use_sim_time=use_sim_time,
    )
    problem = load_problem(domain, state, goal, weights, sequence=True, lasting=True)
    config: Configuration | None = None
    parts: list[Part] = []
    registry: Registry | None = None
    if (
        kind == "zenoh"
        and reconfigure
        and robot in problem.task.agents
        and not (ros2 or ros2_map or live or foxglove)  # they show the configuration
        and never_coordinates(problem.task, problem.goal_calls, robot)
    ):  # it follows the coordinator: it plans if its implementations may not run a part
        try:
            registry = Registry.load(impl)
        except RunError as exc:
            raise run_error(exc) from None
        if not registry.serves(objects_and_inputs(problem)):
            registry = None  # its part is checked at start, as the coordinator's
    if registry is None:  # the coordinator plans; so does every robot without one
        config = planned(problem, rank)
        parts = runtime_parts(config, problem)
    options = RunOptions(
        rate=rate,
        cycles=cycles,
        duration=duration,
        stale_periods=stale_periods,
        budget=budget or None,
        max_value_bytes=max_value_bytes,
        trace=None if trace is None else str(trace),
        trace_max_bytes=trace_max_bytes,
        force=force,
        verbose=verbose,
    )
    settings = Settings(
        injections(inject, problem), reconfigure, hold, margin, without=without_coordinator
    )
    opened: Transport | None = None
    bound: Bindings | None = None  # --ros2-map's
    ros_node = None  # the rclpy node of --ros2 / --ros2-map (--ros2-via rclpy)
    ros_events = None  # its listener of the society's events (--ros2)
    written: TraceFile | None = None
    recording = None
    fox = None
    try:
        if registry is None:
            registry = Registry.load(impl)
        if robot is None:
            running = society(parts, registry)
        else:
            part = next((p for p in parts if p.robot == robot), None)
            if part is None and not (reconfigure and robot in problem.task.agents):
                names = ", ".join(p.robot for p in parts)
                raise RunError(
                    f"no robot {robot} in this configuration (its robots: {names})",
                    hint=did_you_mean(robot, problem.task.agents),
                )
            part = part or Part(robot, (), ())  # a robot of the state, or that follows: it waits
            topics = None
            if ros2_map is not None:  # checked against the domain before the network opens
                from cfgplan.ros2.topics import load_map

                topics = load_map(ros2_map, problem.domain, problem.task.agents)
            registry.require(
                c.name for c in part.calls if topics is None or not topics.implements(c.name, robot)
            )
            zenoh = network_options(
                society_name,
                listen or (),
                connect or (),
                None if zenoh_config is None else str(zenoh_config),
                lease,
                None if keys is None else str(keys),
                problem=problem_id(problem, domain, state),
                allowance=rate_allowance,
                router=router or (),
                plans=reconfigure,  # it may take over coordination (5.5)
            )
            via = None
            if ros2 or topics is not None:  # rclpy is imported only if so chosen
                from cfgplan.ros2.node import choose_via

                via = choose_via(ros2_via)
            opened = open_transport(robot, kind, zenoh)
            if via == "rclpy":  # a real ROS 2 node (cfgplan.ros2.node)
                from cfgplan.ros2.bridge import domain_id_of
                from cfgplan.ros2.node import NodeOptions, RosNode

                ros_node = RosNode(
                    robot, NodeOptions(domain_id_of(ros_domain_id), use_sim_time=use_sim_time)
                )
            if topics is not None:  # bound functionalities read and publish ROS 2 topics
                if ros_node is not None:
                    from cfgplan.ros2.node import RclpyBindings

                    bound = RclpyBindings(ros_node, robot, topics, max_value_bytes)
                else:
                    from cfgplan.ros2.bindings import open_bindings

                    bound = open_bindings(opened, robot, topics, ros_domain_id, max_value_bytes)
                registry = bound.registry(registry)
            shared = opened if isinstance(opened, InProcessTransport) else None
            running = Society([build(part, registry, opened)], shared)
            if ros2 and ros_node is not None:  # the society's events on the node's topics
                from cfgplan.ros2.node import RclpyEvents

                assert config is not None  # --ros2: planned
                ros_events = RclpyEvents(ros_node, robot, config)
                running.subscribe(ros_events)
            elif ros2:  # its Adaptation events on /cfgplan/events (cfgplan.ros2)
                from cfgplan.ros2.bridge import open_bridge

                running.subscribe(open_bridge(opened, robot, ros_domain_id))
        if options.trace is not None:
            written = open_trace(options.trace, options.force, max_bytes=options.trace_max_bytes)
        adapting = hooks(
            running, registry, problem, config, parts, settings, written, whole=robot is None
        )
        if ros_events is not None:  # /cfgplan/configuration follows the coordinator's
            ros_events.follow(adapting)
        names = ", ".join(r.name for r in running.robots)
        lasting = how_long(options.cycles, options.duration)
        if record is not None:  # mcap is imported only then (cfgplan.record)
            from cfgplan.record.launch import start_recording
            from cfgplan.record.policy import Policy

            recording = start_recording(record, force, Policy(max_bytes=record_max_bytes))
            running.subscribe(recording)
        if foxglove is not None:  # foxglove-sdk is imported only then
            from cfgplan.record.launch import open_foxglove

            assert config is not None  # --foxglove: planned
            heading = heading_of(problem, config, rank)
            fox = open_foxglove(foxglove, running, adapting, config, problem.goal_call, heading)
            running.subscribe(fox)
        page = None
        if live is not None:  # aiohttp is imported only then (cfgplan.live)
            from cfgplan.live.launch import open_live

            assert config is not None  # --live: planned
            heading = heading_of(problem, config, rank)
            page = open_live(live, running, adapting, problem, config, heading)
        try:
            code = execute(
                running,
                options,
                source=registry.source,
                trace=written,
                hooks=adapting,
                heading=f"{heading_of(problem, config, rank)}: {names}; {lasting}",
                lead=None if config is None else coordinator_of(problem.goal_call, config),
            )
        finally:
            if page is not None:
                page.stop()
            if fox is not None:
                fox.stop()
            if recording is not None:
                recording.close()
            if ros_node is not None:  # destroyed at the end, SIGINT and SIGTERM too
                ros_node.close()
        for line in [] if bound is None else bound.summary():  # after the run's own
            print(f"ros2: {line}")
        if recording is not None and recording.failed:
            print(f"cfgplan: error: {recording.failed}", file=sys.stderr)
            code = code or 1
    except RunError as exc:
        if ros_node is not None:
            ros_node.close()
        if opened is not None:
            opened.close()
        if written is not None:
            written.close()
        if recording is not None:
            recording.close()
        if fox is not None:
            fox.stop()
        raise run_error(exc) from None
    if code:
        raise typer.Exit(code)


def planned(problem: "Problem", rank: int) -> "Configuration":
    """The configuration of ``rank`` the society starts with (of the first step
    of a sequence); exit 3 when there is none."""
    if len(problem.goals) > 1:
        from cfgplan.cli.sequence import first_step

        return first_step(problem, rank)
    return choose(problem, rank)


def runtime_parts(config: "Configuration", problem: "Problem") -> list[Part]:
    """``config`` per robot, sorted, divided and wired (5.1-5.3) for the runtime."""
    from cfgplan.backends.part import runtime_part
    from cfgplan.backends.wiring import deploy

    return [runtime_part(p, config.cost) for p in deploy(config, problem.domain)]


def objects_and_inputs(problem: "Problem") -> list[tuple[str, int, int]]:
    """Each functionality of the domain: its name, object arguments (those
    after the robot) and inputs, as an implementation is called."""
    return [
        (name, arity - 1, len(schema.inputs))
        for (name, arity), schema in problem.task.functionalities.items()
    ]


def heading_of(problem: "Problem", config: "Configuration | None", rank: int) -> str:
    """What a run says first: its configuration, or, for a robot that plans
    nothing, that it follows the coordinator."""
    if config is None:
        return f"Following the coordinator, for {call_text(problem.goal_call)}"
    from cfgplan.cli.emit import title

    return title(problem, config, rank)


def refuse_combinations(
    kind: str,
    *,
    keys: Path | None,
    ros2: bool,
    ros2_map: Path | None,
    ros_domain_id: int | None,
    ros2_via: str | None,
    use_sim_time: bool,
) -> None:
    """Refuse options that do not go together (exit 2); ``kind`` is the
    transport. ``cfgplan launch`` asks the same of the options of run it passes
    on (each robot runs over Zenoh), before any robot starts."""
    if keys is not None and kind != "zenoh":
        usage_error("secures the network between robots: give --robot NAME", "--keys")
    if ros2 and kind != "zenoh":
        usage_error("publishes over the robot's Zenoh session: give --robot NAME", "--ros2")
    if ros2 and keys is not None:  # mTLS and deny-by-default access control: no ROS node gets in
        usage_error("cannot be combined with --keys yet (docs: Use cfgplan with ROS 2)", "--ros2")
    if ros2_map is not None and kind != "zenoh":
        usage_error("binds topics on the robot's Zenoh session: give --robot NAME", "--ros2-map")
    if ros2_map is not None and keys is not None:
        usage_error(
            "cannot be combined with --keys yet (docs: Use cfgplan with ROS 2)", "--ros2-map"
        )
    if ros_domain_id is not None and not (ros2 or ros2_map):
        usage_error("is the ROS domain of --ros2: give --ros2", "--ros-domain-id")
    if ros2_via not in (None, "rclpy", "zenoh"):
        usage_error(f"{ros2_via!r}: give rclpy or zenoh", "--ros2-via")
    for flag, given in (("--ros2-via", ros2_via is not None), ("--use-sim-time", use_sim_time)):
        if given and not (ros2 or ros2_map):
            usage_error("says how --ros2 and --ros2-map speak ROS 2: give one of them", flag)
