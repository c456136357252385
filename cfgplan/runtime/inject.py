"""Scripted faults (``--inject``), applied to the robots of this process (5.5).

An :class:`Injector` is the ``before`` hook of
:meth:`cfgplan.runtime.Society.run`: before each cycle it applies the
injections that are due (:meth:`~cfgplan.runtime.faults.Injection.due`, by
the cycle about to run or the seconds since the run began) and records an
``inject`` event on the robot concerned:

* ``fail X`` — every call of instance X fails from then on, as if its
  implementation raised :class:`~cfgplan.runtime.faults.ResourceFailure`
  (the implementation is not called); it holds for any wrapper of X the
  robot runs later, until ``recover X``;
* ``kill R`` — robot R is gone: in one process it stops running and the
  others see it lost; a robot of its own process ends at once, as a crash
  (no goodbye: the others see its connection close);
* ``recover R`` — in one process, robot R is back, running nothing until it
  is given a part;
* ``assert F`` / ``retract F`` — an operator's state update, recorded for
  the monitor (only in the process that plans).

Injections aimed at robots of other processes are left to those processes
(give every process the same ``--inject`` options).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.faults import Injection
from cfgplan.runtime.install import crash
from cfgplan.runtime.society import Society

__all__ = ["Injector", "Scripted"]


class Injector:
    """Applies ``injections`` to ``society`` as they fall due."""

    def __init__(
        self,
        injections: Sequence[Injection],
        society: Society,
        *,
        facts: bool = True,
        kill: Callable[[str], None] | None = None,
    ) -> None:
        self.pending = [i for i in injections if self._ours(i, society, facts)]
        self.society = society
        self.kill = kill or self._crash
        self.applied: list[Injection] = []

    def _crash(self, name: str) -> None:
        """In one process: the robot stops, loses its part and is seen lost."""
        robot = self.society.robot(name)
        if robot is not None:
            crash(robot)
        self.society.kill(name)

    @staticmethod
    def _ours(injection: Injection, society: Society, facts: bool) -> bool:
        if injection.on_facts:
            return facts
        return society.robot(injection.robot or "") is not None

    def __call__(self, cycle: int, elapsed: float) -> None:
        due = [i for i in self.pending if i.due(cycle, elapsed)]
        for injection in due:
            self.pending.remove(injection)
            self.applied.append(injection)
            self._apply(injection, cycle)

    def _apply(self, injection: Injection, cycle: int) -> None:
        robot = self.society.robot(injection.robot or "") or self.society.robots[0]
        robot.record(
            Adaptation(
                robot=robot.name,
                cycle=cycle,
                t=time.time(),
                what="inject",
                info=(
                    ("spec", injection.text),
                    ("action", injection.action),
                    ("target", injection.target),
                ),
            )
        )
        if injection.action == "kill":
            self.kill(robot.name)
        elif injection.on_robot:  # recover ROBOT
            self.society.revive(robot.name)
        elif injection.action == "fail":
            _fault(robot, injection.target, injection.text)
        elif injection.action == "recover":
            _fault(robot, injection.target, None)


def _fault(robot: Robot, instance: tuple[str, ...], text: str | None) -> None:
    """Set (or lift, ``None``) a scripted fault on ``instance``."""
    if text is None:
        robot.faults.pop(instance, None)
    else:
        robot.faults[instance] = text
    for wrapper in robot.wrappers:
        if (wrapper.name, wrapper.robot, *wrapper.objects) == instance:
            wrapper.injected = text


class Scripted:
    """Hooks for :func:`cfgplan.runtime.execute` that only inject faults
    (``--no-reconfigure``): the faults happen, nobody reconfigures."""

    def __init__(self, injector: Injector) -> None:
        self.injector = injector
        self.finished: str | None = None
        self.stopped = False
        self.reconfigures = False

    def before(self, cycle: int, elapsed: float) -> None:
        self.injector(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        """Nothing: no reconfiguration."""

    @property
    def refusal(self) -> None:
        """Scripted faults refuse nothing."""
        return None

    def close(self) -> None:
        """Nothing runs beside the loop."""
