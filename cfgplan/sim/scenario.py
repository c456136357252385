"""Scenario files: a domain, a state, goals, and the world the robots act in.

A scenario is a TOML file (docs/how-to/write-a-scenario.md): which domain and state to
plan with (paths relative to the scenario file), the goals (else the state's
``(goal ...)`` or ``(sequence ...)``), the implementations (a module name or a
``.py`` file), the world (rooms and doors as in 6.2.1, magnetic
disturbances, a bar, blocks and walls), each robot's start pose, sensors and
task parameters, scripted faults (the runtime's ``--inject`` syntax) and
world changes, how long to run and the seed. Angles are written in degrees.

This module is the model (pydantic, every key known); :mod:`cfgplan.sim.reading`
reads a file into it and checks it, each problem an error at its place in the
file (``file:line:col`` and a caret), never a traceback.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from cfgplan.diagnostics import Diagnostic
from cfgplan.sim.locate import locate

__all__ = [
    "SENSORS",
    "Bar",
    "Block",
    "Door",
    "Event",
    "Loaded",
    "Magnetic",
    "RobotSpec",
    "Scenario",
    "WallObject",
    "World",
    "parse_sensor",
    "room_of",
    "sensor_problem",
]

SensorName = Literal["camera", "compass", "odometry", "laser", "sonar"]
SENSORS: tuple[SensorName, ...] = ("camera", "compass", "odometry", "laser", "sonar")

Point = tuple[float, float]
Box = tuple[float, float, float, float]


class Strict(BaseModel):
    """Every key is known (a misspelt one is an error), values are final."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


class Door(Strict):
    """A door in a wall between two rooms: its centre, width and direction of passage."""

    at: Point
    width: float = Field(gt=0)
    passage: float  # degrees


class Magnetic(Strict):
    """A magnetic disturbance: compasses near ``at`` read ``deflection`` degrees
    off, fading with the distance (a Gaussian of deviation ``radius``)."""

    at: Point
    radius: float = Field(gt=0)
    deflection: float
    start: float = Field(default=0.0, ge=0, alias="from")
    until: float | None = None


class Bar(Strict):
    """A bar resting on two robots (6.3.1): dropped when their distance leaves
    ``length`` ± ``tolerance``."""

    robots: tuple[str, str]
    length: float = Field(gt=0)
    tolerance: float = Field(gt=0)


class Block(Strict):
    """A wall block (6.4): its centre, the heading of its long faces' normal,
    its size (length, thickness), the robots pushing its back face, and the
    wall it must be aligned with (within ``tolerance``: metres, degrees)."""

    at: Point
    heading: float
    size: tuple[float, float]
    pushers: dict[Literal["left", "right"], str] = Field(default_factory=dict)
    contact: float = Field(default=0.45, gt=0)
    target: str | None = None
    tolerance: tuple[float, float] = (0.05, 3.0)


class WallObject(Strict):
    """A built wall (W1 of 6.4): a fixed block row whose free end, ``left`` or
    ``right`` seen along ``heading``, is where the next block goes, ``gap`` away."""

    at: Point
    heading: float
    size: tuple[float, float]
    free_end: Literal["left", "right"] = "left"
    gap: float = Field(default=0.02, ge=0)


class World(Strict):
    rooms: dict[str, Box]
    doors: dict[str, Door] = Field(default_factory=dict)
    obstacles: list[Box] = Field(default_factory=list)
    magnetic: list[Magnetic] = Field(default_factory=list)
    bar: Bar | None = None
    blocks: dict[str, Block] = Field(default_factory=dict)
    walls: dict[str, WallObject] = Field(default_factory=dict)
    marks: dict[str, Point] = Field(default_factory=dict)


class CameraSpec(Strict):
    """A fixed camera (6.2.1): bearings within ``fov``, range and a door's
    orientation only for objects beyond ``min_range``."""

    fov: float = Field(default=90.0, gt=0, le=360)
    min_range: float = Field(default=2.0, ge=0)
    max_range: float = Field(default=7.0, gt=0)
    bearing_noise: float = Field(default=0.5, ge=0)  # degrees
    range_noise: float = Field(default=0.01, ge=0)  # share of the range
    orient_noise: float = Field(default=1.5, ge=0)  # degrees


class CompassSpec(Strict):
    noise: float = Field(default=1.0, ge=0)  # degrees


class LaserSpec(Strict):
    fov: float = Field(default=180.0, gt=0, le=360)
    beams: int = Field(default=361, ge=2, le=4000)
    max_range: float = Field(default=8.0, gt=0)
    noise: float = Field(default=0.005, ge=0)  # metres


class SonarSpec(Strict):
    beams: int = Field(default=16, ge=2, le=360)
    max_range: float = Field(default=5.0, gt=0)
    noise: float = Field(default=0.005, ge=0)  # metres, plus 1 % of the range


class OdometrySpec(Strict):
    scale: float = Field(default=0.01, ge=0)  # share: the wheels' calibration error
    drift: float = Field(default=1.0, ge=0)  # degrees of heading error per metre
    noise: float = Field(default=0.005, ge=0)  # metres per metre travelled


class Sensors(Strict):
    camera: CameraSpec = CameraSpec()
    compass: CompassSpec = CompassSpec()
    laser: LaserSpec = LaserSpec()
    sonar: SonarSpec = SonarSpec()
    odometry: OdometrySpec = OdometrySpec()


class Motion(Strict):
    """Unicycle robots (40 cm discs, 6.1): limits, actuation noise, and the
    watchdog that stops a robot whose commands stop coming. A robot's body
    stands below the lasers' plane; a laser sees its post (the stand that
    holds the bar, 6.3.1) of radius ``post`` at its centre."""

    radius: float = Field(default=0.2, gt=0)
    post: float = Field(default=0.05, gt=0)  # the radius of the post a laser sees
    max_speed: float = Field(default=0.4, gt=0)
    max_turn: float = Field(default=90.0, gt=0)  # degrees per second
    noise: float = Field(default=0.02, ge=0)  # share of the speed
    watchdog: float = Field(default=0.3, gt=0)  # seconds


class RobotSpec(Strict):
    at: tuple[float, float, float] | None = None  # x, y, heading (degrees); pushers: none
    has: list[SensorName] | None = None  # default: every sensor
    camera: CameraSpec | None = None
    compass: CompassSpec | None = None
    laser: LaserSpec | None = None
    sonar: SonarSpec | None = None
    odometry: OdometrySpec | None = None
    params: dict[str, Any] = Field(default_factory=dict)


class Event(Strict):
    """A world change at ``at`` seconds: a sensor breaks or is repaired
    (``"laser(Emil)"``), or a magnetic disturbance appears."""

    at: float = Field(ge=0)
    breaks: str | None = Field(default=None, alias="break")
    repair: str | None = None
    magnetic: Magnetic | None = None


class Expect(Strict):
    rooms: dict[str, str] = Field(default_factory=dict)


class Scenario(Strict):
    name: str
    title: str = ""
    domain: str
    state: str
    goals: list[str] = Field(default_factory=list)
    rank: int = Field(default=1, ge=1)  # start with the configuration (or sequence) of this rank
    impl: str
    seed: int = 1
    duration: float = Field(default=120.0, gt=0, le=3600)
    step: float = Field(default=0.1, gt=0, le=1)
    world: World
    sensors: Sensors = Sensors()
    motion: Motion = Motion()
    robots: dict[str, RobotSpec]
    faults: list[str] = Field(default_factory=list)
    events: list[Event] = Field(default_factory=list)
    expect: Expect = Expect()

    def sensor(self, robot: str, kind: SensorName) -> Any:
        """The spec of ``robot``'s sensor ``kind`` (its own, else the defaults)."""
        own = getattr(self.robots[robot], kind)
        return own if own is not None else getattr(self.sensors, kind)

    def carries(self, robot: str, kind: SensorName) -> bool:
        has = self.robots[robot].has
        return has is None or kind in has


@dataclass(frozen=True)
class Loaded:
    """A scenario as read, with where it came from (to resolve paths and quote lines)."""

    scenario: Scenario
    file: str
    text: str
    folder: Path

    def path(self, relative: str) -> Path:
        """A path of the scenario, relative to its file."""
        p = Path(relative)
        return p if p.is_absolute() else self.folder / p

    def where(self, *path: str | int) -> Any:
        """The span of a key, for messages."""
        return locate(self.text, self.file, path)

    def problem(self, message: str, *path: str | int, hint: str | None = None) -> Diagnostic:
        return Diagnostic("error", message, self.where(*path), hint)


_SENSOR = re.compile(r"^\s*\(?\s*([a-z]+)\s*[\s(]\s*([^\s()]+)\s*\)?\s*$")


def parse_sensor(text: str) -> tuple[SensorName, str] | None:
    """``laser(Emil)`` or ``(laser Emil)``: the sensor and its robot."""
    m = _SENSOR.match(text)
    if m is None or m.group(1) not in SENSORS:
        return None
    kind: SensorName = m.group(1)  # type: ignore[assignment]
    return kind, m.group(2)


def sensor_problem(text: str, robots: Sequence[str] | set[str]) -> str | None:
    parsed = parse_sensor(text)
    if parsed is None:
        return f"{text!r}: expected a sensor such as laser(Emil) ({', '.join(SENSORS)})"
    if parsed[1] not in robots:
        return f"{text!r}: no robot {parsed[1]} in robots"
    return None


def room_of(rooms: dict[str, Box], x: float, y: float) -> str | None:
    """The room whose box holds (x, y), the first one listed when several do."""
    for name, (x0, y0, x1, y1) in rooms.items():
        if x0 <= x <= x1 and y0 <= y <= y1:
            return name
    return None
