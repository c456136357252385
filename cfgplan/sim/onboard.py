"""What an implementation may touch in the simulator: its own robot's hardware.

An implementation of a functionality (``@functionality("compass")``) runs on
a robot (:func:`cfgplan.runtime.current_robot`); in a simulation
:func:`hardware` gives it that robot's sensors and motors, and what the
robot knows before it starts — never the true state of the world. Sensing
functionalities read sensors; action functionalities drive the motors with
what they received through the configuration's channels (5.2.1)::

    from cfgplan.runtime import functionality
    from cfgplan.sim import hardware

    @functionality("compass")
    def compass() -> float:
        return hardware().compass()

* ``camera()``, ``compass()``, ``odometry()``, ``laser()``, ``sonar()`` —
  readings (:mod:`cfgplan.sim.sensors`); a broken sensor, or one the robot
  does not carry, raises :class:`~cfgplan.runtime.ResourceFailure`;
* ``drive(speed, turn)`` (m/s, rad/s) and ``halt()`` — the motors keep a
  command for the watchdog's time only;
* ``clock()`` — the robot's clock (simulated seconds);
* ``params`` — the robot's task parameters from the scenario (where to go
  after a door, the leader's route, which side of a block it pushes);
* ``knowledge`` — its map (walls as segments) and the sizes of the objects
  it may meet, known in advance, as a real robot's map is;
* ``missing(instance, text)`` — this instance has no data this time, and why
  (kept for the scenario's report); after :data:`MISSING` seconds without
  any it raises :class:`~cfgplan.runtime.ResourceFailure`; ``found(instance)``
  when it has data again.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import ResourceFailure
from cfgplan.runtime.wrapper import current_robot
from cfgplan.sim import sensors
from cfgplan.sim.world import World

__all__ = ["Hardware", "Knowledge", "hardware", "simulating"]

MISSING = 2.0
"""Seconds without data after which a measurement counts as failed (:meth:`Hardware.missing`)."""

_active: list[World] = []
_notes: dict[str, tuple[float, str]] = {}


@dataclass(frozen=True)
class Knowledge:
    """What every robot knows before it starts: the map and the objects' sizes."""

    walls: tuple[tuple[float, float, float, float], ...]
    """The building's walls as segments (x1, y1, x2, y2), for localization."""
    blocks: dict[str, tuple[float, float]]
    """Each block's (length, thickness)."""
    built: dict[str, dict[str, Any]]
    """Each built wall's ``size``, ``free_end`` and ``gap``."""
    radius: float
    """The robots' radius."""
    post: float
    """The radius of a robot's post, which lasers see."""


@contextmanager
def simulating(world: World) -> Iterator[None]:
    """Implementations called inside see ``world`` through :func:`hardware`."""
    _active.append(world)
    _notes.clear()
    try:
        yield
    finally:
        _active.pop()


def notes() -> dict[str, tuple[float, str]]:
    """The latest note of each instance: (time, text)."""
    return dict(_notes)


class Hardware:
    """One robot's sensors and motors (module docstring)."""

    def __init__(self, world: World, robot: str) -> None:
        self._world = world
        self.robot = robot
        spec = world.scenario.robots[robot]
        self.params: dict[str, Any] = dict(spec.params)
        body = world.bodies[robot]
        if body.attached is not None:
            block = world.blocks[body.attached.block]
            self.params.setdefault(
                "push",
                {
                    "block": block.name,
                    "side": body.attached.side,
                    "contact": abs(body.attached.offset),
                },
            )
        s = world.scenario
        self.knowledge = Knowledge(
            walls=tuple(world.segments),
            blocks={n: b.size for n, b in s.world.blocks.items()},
            built={
                n: {"size": w.size, "free_end": w.free_end, "gap": w.gap}
                for n, w in s.world.walls.items()
            },
            radius=s.motion.radius,
            post=s.motion.post,
        )

    def camera(self) -> dict[str, Any]:
        return sensors.camera(self._world, self.robot)

    def compass(self) -> float:
        return sensors.compass(self._world, self.robot)

    def odometry(self) -> list[float]:
        return sensors.odometry(self._world, self.robot)

    def laser(self) -> dict[str, Any]:
        return sensors.scan(self._world, self.robot, "laser")

    def sonar(self) -> dict[str, Any]:
        return sensors.scan(self._world, self.robot, "sonar")

    def drive(self, speed: float, turn: float) -> None:
        self._world.bodies[self.robot].drive(self._world.time, speed, turn)

    def halt(self) -> None:
        self.drive(0.0, 0.0)

    def clock(self) -> float:
        return self._world.time

    def memory(self, key: str) -> dict[str, Any]:
        """A place for an implementation to keep state between calls (a
        functionality "with a memory", 6.3.2), fresh for every simulation."""
        return self._world.memories.setdefault((self.robot, key), {})

    @property
    def max_speed(self) -> float:
        return self._world.scenario.motion.max_speed

    @property
    def watchdog(self) -> float:
        """Seconds the motors keep a command."""
        return self._world.scenario.motion.watchdog

    @property
    def max_turn(self) -> float:
        return math.radians(self._world.scenario.motion.max_turn)

    def note(self, instance: str, text: str) -> None:
        _notes[instance] = (round(self._world.time, 3), text)

    def missing(self, instance: str, text: str, limit: float = MISSING) -> None:
        """``instance`` has no data this time, because of ``text``: noted, and
        once it has had none for ``limit`` seconds running, its resource has
        failed (:class:`~cfgplan.runtime.ResourceFailure`): a measurement
        that cannot measure for that long is as good as broken, and the
        society re-plans without it (5.5)."""
        self.note(instance, text)
        memory = self.memory(f"missing {instance}")
        since = memory.setdefault("since", self._world.time)
        if self._world.time - since >= limit - 1e-9:
            memory.clear()
            raise ResourceFailure(f"no data for {limit:g} s: {text}")

    def found(self, instance: str) -> None:
        """``instance`` has data again (see :meth:`missing`)."""
        self.memory(f"missing {instance}").clear()


def hardware(robot: str | None = None) -> Hardware:
    """The hardware of ``robot`` (default: the robot whose functionality runs)."""
    if not _active:
        raise RunError(
            "cfgplan.sim.hardware() is only available while a simulation runs (cfgplan simulate)"
        )
    world = _active[-1]
    name = current_robot() if robot is None else robot
    if name not in world.bodies:
        raise RunError(f"robot {name} has no body in this simulation")
    return Hardware(world, name)
