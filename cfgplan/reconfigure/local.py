"""Monitoring and reconfiguration of a society run in one process (``cfgplan run``, 5.5).

:func:`adapt` sets it up around a :class:`~cfgplan.runtime.Society`: a
:class:`~cfgplan.runtime.monitor.Monitor` on every robot, the scripted
faults (:class:`~cfgplan.runtime.inject.Injector`), and a
:class:`~cfgplan.reconfigure.coordinate.Coordinator` whose deployer installs
each robot's part directly (:func:`cfgplan.runtime.install.install`),
between two cycles: every robot switches before the next cycle, so no cycle
runs half of two configurations. A robot a new configuration needs that is
not running yet joins the society. The hooks go to
:func:`cfgplan.runtime.execute`.

Sequences of configurations (7.3) can reuse :meth:`Adaptive.install`:
put configuration X on the running society with the least disruption.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Domain
from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.ahead import Ahead
from cfgplan.reconfigure.coordinate import Coordinator, Done, Failed
from cfgplan.reconfigure.decision import Decision, Hysteresis
from cfgplan.reconfigure.owner import coordinator_of
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.faults import Injection
from cfgplan.runtime.inject import Injector
from cfgplan.runtime.install import install
from cfgplan.runtime.monitor import HOLD, Monitor
from cfgplan.runtime.part import Part
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.society import Society

__all__ = ["Adaptive", "InProcessDeployer", "adapt", "coordinator_of"]


class InProcessDeployer:
    """Installs every robot's part at once (the robots share this process)."""

    def __init__(self, society: Society, registry: Registry, monitor: Monitor) -> None:
        self.society = society
        self.registry = registry
        self.monitor = monitor

    def robot(self, name: str) -> Robot:
        """Robot ``name``, joining the society (and the monitor) if it is new."""
        found = self.society.robot(name)
        if found is None:
            found = Robot(name, self.registry, self.society.transport, clock=self.society.clock)
            found.configure(lambda r: lambda: None)
            self.society.add(found)
            self.monitor.watch(found)
        return found

    def deploy(
        self, decision: Decision, parts: dict[str, Part], done: Done, failed: Failed
    ) -> None:
        for name, part in parts.items():
            robot = self.robot(name)
            if not robot.alive:
                continue
            installed = install(robot, part)
            robot.record(
                Adaptation(
                    robot=name,
                    t=time.time(),
                    what="install",
                    info=(("id", decision.id), *installed.record()),
                )
            )
        done()


@dataclass
class Adaptive:
    """The hooks :func:`cfgplan.runtime.execute` runs a self-reconfiguring society with."""

    coordinator: Coordinator
    monitor: Monitor
    injector: Injector

    def before(self, cycle: int, elapsed: float) -> None:
        self.injector(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        for detection in self.monitor.drain():
            self.coordinator.handle(detection)
        self.coordinator.tick()

    @property
    def finished(self) -> str | None:
        return self.coordinator.finished

    @property
    def refusal(self) -> None:
        """In one process nobody can be refused."""
        return None

    @property
    def stopped(self) -> bool:
        """The run ends with nothing admissible running."""
        return self.coordinator.stopped

    @property
    def reconfigures(self) -> bool:
        return True

    def close(self) -> None:
        self.coordinator.close()


def adapt(
    society: Society,
    registry: Registry,
    task: Task,
    domain: Domain,
    goal: Ground,
    config: Configuration,
    injections: Sequence[Injection] = (),
    *,
    hysteresis: Hysteresis | None = None,
    hold: float = HOLD,
    goals: tuple[Ground, ...] = (),
    clock: Callable[[], float] | None = None,
    ahead: bool = True,
) -> Adaptive:
    """Monitor ``society`` (running ``config``) and reconfigure it on failures.

    For simulation (deterministic runs): ``clock`` times stale suspicions
    (default: the society's clock); ``ahead=False`` computes the fallbacks
    one per pass of the loop on the robots' thread instead of on a thread of
    their own, so that every decision is the same from run to run."""
    monitor = Monitor(hold=hold)
    for robot in society.robots:
        monitor.watch(robot)
    reconfigurator = Reconfigurator(
        task, domain, goal, config, hysteresis or Hysteresis(), goals=goals
    )
    owner = coordinator_of(goal, config)
    deployer = InProcessDeployer(society, registry, monitor)
    recorder = deployer.robot(owner)
    if society.transport is not None:
        society.transport.presence_listeners.append(monitor.presence(owner))
    coordinator = Coordinator(
        reconfigurator,
        recorder.record,
        owner,
        deployer,
        clock=clock or society.clock,
        ahead=Ahead(reconfigurator) if ahead else None,
        hold=hold,
    )
    return Adaptive(coordinator, monitor, Injector(injections, society))
