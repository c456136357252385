"""Robots' bodies: unicycle kinematics, the motors' watchdog, odometry, bumps.

A robot is a 40 cm disc (the Magellan Pro of 6.1) driven by a forward speed
and a turn rate. The motors keep a command for ``watchdog`` seconds only:
an action that stops being called (its data stopped coming) leaves its
robot standing, as a real base's safety timeout does. The speeds executed
differ from those commanded by a little seeded noise (wheel slip); the
odometry integrates what the wheels did with a scale error and a heading
drift per metre, so dead reckoning wanders off the truth. A robot that
would overlap a wall, a block or another robot does not move (it may still
turn); each new contact counts as a bump.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from cfgplan.sim.geometry import Pose, wrap
from cfgplan.sim.scenario import Motion, OdometrySpec

__all__ = ["Attachment", "Body"]


@dataclass
class Attachment:
    """A robot pushing a block's back face at a lateral offset (6.4)."""

    block: str
    side: str  # left or right of the push direction
    offset: float  # along the block's long axis, left positive
    delta: float = 0.0  # the robot's heading relative to the push direction


@dataclass
class Body:
    """One simulated robot: its true pose, its motors and its odometry."""

    name: str
    pose: Pose
    motion: Motion
    odometry_spec: OdometrySpec
    rng: random.Random
    command: tuple[float, float] = (0.0, 0.0)
    until: float = -1.0  # the command holds until then (the watchdog)
    odometry: Pose = (0.0, 0.0, 0.0)
    broken: set[str] = field(default_factory=set)
    attached: Attachment | None = None
    bumps: int = 0
    touching: bool = False
    travelled: float = 0.0
    scale: float = 1.0  # the odometry's calibration error, drawn once

    def __post_init__(self) -> None:
        self.odometry = self.pose  # dead reckoning starts from the known start pose
        self.scale = 1.0 + self.rng.gauss(0.0, self.odometry_spec.scale)

    @property
    def radius(self) -> float:
        return self.motion.radius

    def drive(self, now: float, speed: float, turn: float) -> None:
        """Command the motors (clipped to the robot's limits) for the watchdog's time."""
        top, spin = self.motion.max_speed, math.radians(self.motion.max_turn)
        if not (math.isfinite(speed) and math.isfinite(turn)):
            speed, turn = 0.0, 0.0
        self.command = (max(-top, min(top, speed)), max(-spin, min(spin, turn)))
        self.until = now + self.motion.watchdog

    def commanded(self, now: float) -> tuple[float, float]:
        """What the motors do now: the command, or nothing once it expired."""
        return self.command if now < self.until else (0.0, 0.0)

    def executed(self, now: float, h: float) -> tuple[float, float]:
        """The speeds the wheels actually give over a step of ``h`` seconds."""
        v, w = self.commanded(now)
        if v == 0.0 and w == 0.0:
            return 0.0, 0.0
        k = self.motion.noise
        return v * (1 + self.rng.gauss(0.0, k)), w + self.rng.gauss(0.0, k) * (abs(w) + 0.05)

    def moved(self, before: Pose, after: Pose) -> None:
        """The body went from ``before`` to ``after``: the odometry follows, with its errors."""
        ds = math.hypot(after[0] - before[0], after[1] - before[1])
        heading_change = wrap(after[2] - before[2])
        forward = (after[0] - before[0]) * math.cos(before[2]) + (after[1] - before[1]) * math.sin(
            before[2]
        )
        spec = self.odometry_spec
        ds_o = math.copysign(ds, forward) * self.scale + self.rng.gauss(0.0, spec.noise) * ds
        dth_o = heading_change + math.radians(spec.drift) * ds
        x, y, th = self.odometry
        mid = th + dth_o / 2
        self.odometry = (x + ds_o * math.cos(mid), y + ds_o * math.sin(mid), wrap(th + dth_o))
        self.travelled += ds
        self.pose = after
