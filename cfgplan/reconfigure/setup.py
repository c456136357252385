"""Choosing how a run monitors and reconfigures itself (``cfgplan run``, 5.5).

:func:`hooks` returns what :func:`cfgplan.runtime.execute` gets:

* every robot in this process: :func:`~cfgplan.reconfigure.local.adapt`
  (``--no-reconfigure``: only the scripted faults);
* one robot alone (``--transport inprocess``): only the scripted faults;
* one robot on the network: the robot that owns the goal coordinates
  (:func:`~cfgplan.reconfigure.network.coordinate`), any other follows it
  (:class:`~cfgplan.runtime.member.Membership`; one that may never
  coordinate watches only the robots it needs,
  :meth:`~cfgplan.runtime.zenoh_transport.ZenohTransport.narrow`, and
  needs no plan at start); both apply the scripted
  faults aimed at their own robot, and only the coordinator the state
  updates. Where the goals name more than one robot (a sequence whose steps
  name others), each such robot may take over coordination, and a
  coordinator may step down (:mod:`~cfgplan.reconfigure.succession`).
  ``kill`` of this process's robot ends the process at once, as a crash:
  the trace is flushed first, nothing else is said to anyone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cfgplan.problem import Problem
from cfgplan.reconfigure.committed import situation_of
from cfgplan.reconfigure.decision import Hysteresis
from cfgplan.reconfigure.owner import coordinator_of, coordinators_of, owner, succession_of
from cfgplan.reconfigure.situation import Situation
from cfgplan.reconfigure.succession import Steward
from cfgplan.runtime.faults import Injection
from cfgplan.runtime.inject import Injector, Scripted
from cfgplan.runtime.launch import Hooks
from cfgplan.runtime.main import crash
from cfgplan.runtime.member import Member, Membership
from cfgplan.runtime.monitor import HOLD, Monitor
from cfgplan.runtime.part import Part
from cfgplan.runtime.protocol import generation
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.society import Society
from cfgplan.runtime.succession import TAKEOVER_AFTER
from cfgplan.runtime.tracefile import TraceFile
from cfgplan.runtime.zenoh_transport import ZenohTransport

if TYPE_CHECKING:
    from cfgplan.configuration.model import Configuration
    from cfgplan.reconfigure.network import NetworkAdaptive

__all__ = ["Settings", "hooks"]


@dataclass(frozen=True)
class Settings:
    """What the command line says about monitoring and reconfiguration."""

    injections: tuple[Injection, ...] = ()
    reconfigure: bool = True
    hold: float = HOLD
    margin: float = 0.1
    without: str = "stop"
    """What a helper does once its coordinator is gone for the hold (``--without-coordinator``)."""
    takeover: float = TAKEOVER_AFTER
    """Seconds the next robot of the order of succession waits, once the
    coordinator's token went, before it takes over."""


def hooks(
    running: Society,
    registry: Registry,
    problem: Problem,
    config: Configuration | None,
    parts: Sequence[Part],
    settings: Settings,
    trace: TraceFile | None = None,
    *,
    whole: bool = True,
) -> Hooks | None:
    """The hooks of a run of ``running`` (module docstring); ``None``: none
    needed. ``whole``: every robot of the configuration runs in ``running``
    (else one robot runs, on the network or alone). ``config`` is ``None``
    for a robot on the network that was planned nothing: one that never
    coordinates (:func:`~cfgplan.reconfigure.owner.never_coordinates`)
    follows the goal's robot (:func:`~cfgplan.reconfigure.owner.owner`)."""
    hysteresis = Hysteresis(margin=settings.margin)
    transport = running.robots[0].transport if len(running.robots) == 1 else None
    if not isinstance(transport, ZenohTransport):
        if settings.reconfigure and whole:
            from cfgplan.reconfigure.local import adapt

            assert config is not None  # every robot here: planned
            return adapt(
                running,
                registry,
                problem.task,
                problem.domain,
                problem.goal_call,
                config,
                settings.injections,
                hysteresis=hysteresis,
                hold=settings.hold,
                goals=problem.goal_calls[1:],
            )
        injector = Injector(settings.injections, running)
        return Scripted(injector) if injector.pending else None
    (robot,) = running.robots

    def kill(name: str) -> None:
        crash(trace)

    if not settings.reconfigure:
        injector = Injector(settings.injections, running, facts=False, kill=kill)
        return Scripted(injector) if injector.pending else None
    agents = frozenset(problem.task.agents)
    goals = problem.goal_calls
    succession = succession_of(goals, agents, coordinators_of(transport, agents), settings.takeover)
    steward = max((len(order) for order in succession.orders), default=0) > 1

    def take_over(following: Membership) -> NetworkAdaptive:
        from cfgplan.reconfigure.network import coordinate  # the planner: loaded now

        member = following.member
        step = min(member.step, len(goals) - 1)
        situation, dropped = (
            (Situation(), ()) if member.known is None else situation_of(member.known, problem.task)
        )
        for line in dropped:  # what the coordinator said that this problem does not know
            member.error(f"what the society committed, dropped: {line}")
        adaptive = coordinate(
            running,
            transport,
            problem.task,
            problem.domain,
            goals[step],
            None,
            {},
            hysteresis=hysteresis,
            hold=settings.hold,
            kill=kill,
            goals=goals[step + 1 :],
            member=member,
            generation=max(1, generation(member.epoch)) + 1,  # none heard yet: the first's
            step=step,
            succession=succession,
            situation=situation,
        )
        if following.injector is not None:
            adaptive.injector = following.injector
        return adaptive

    role: NetworkAdaptive | Membership
    lead = (  # the goal's robot: planned, or told by the goal (a robot that planned nothing)
        coordinator_of(problem.goal_call, config)
        if config is not None
        else owner(problem.task, problem.goal_call) or ""
    )
    if config is not None and robot.name == lead:
        from cfgplan.reconfigure.network import coordinate

        role = coordinate(
            running,
            transport,
            problem.task,
            problem.domain,
            problem.goal_call,
            config,
            {p.robot: p for p in parts},
            settings.injections,
            hysteresis=hysteresis,
            hold=settings.hold,
            kill=kill,
            goals=goals[1:],
            succession=succession if steward else None,
        )
        role.deployer.member.without = settings.without  # should it step down, then lose it
    else:
        successors = {r for order in succession.orders for r in order}
        if robot.name not in successors:  # it never coordinates: it watches only those who do
            transport.narrow(sorted({lead, *successors} - {""}))
        monitor = Monitor(hold=settings.hold)
        monitor.watch(robot)
        member = Member(
            robot,
            transport,
            monitor,
            without=settings.without,
            hold=settings.hold,
            succession=succession if steward else None,
            leader=lead,  # lost before first contact too
        )
        injector = Injector(settings.injections, running, facts=False, kill=kill)
        role = Membership(member, injector)
    return Steward(role, take_over) if steward else role
