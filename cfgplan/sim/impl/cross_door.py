"""Cross a door (thesis 6.2, Appendix A.1 and ``domain-steps.lisp``) in the simulator.

* ``camera`` — the robot's fixed camera: bearings of robots and doors in
  view, their range only beyond 2 m (6.2.1).
* ``compass`` — the heading, **checked against the odometry**: the compass
  learns its offset from the odometry's heading over its first readings,
  then follows it slowly; a reading more than :data:`COMPASS_LIMIT` off what
  the odometry says is a disturbed compass (6.2.2 step 3: "the compass on
  Emil starts to produce incorrect data due to a disturbance in the magnetic
  field"): it raises :class:`~cfgplan.runtime.ResourceFailure`, which the
  monitor takes as ``compass(R)`` failing (5.5).
* ``measure-door``, ``measure-robot-pos``, ``measure-robot-angle`` — read the
  image; no data (``None``) when the object is out of view, or nearer than
  the camera measures.
* ``measure-robot-orient-compass`` — the difference of two headings;
  ``measure-robot-orient-camera`` — the same from the bearings the two robots
  measure to each other (π + a1 − a2: "the robots constantly facing each
  other", 6.2.2).
* ``transform-info`` — the door's pose in the observer's frame, turned into
  the crossing robot's frame.
* ``cross-door`` — the action: with the door's pose relative to itself it
  lines up with the door's axis, drives through and on to its ``target``
  (``params.cross-door.target``: depth beyond the door and offset to the
  left, metres; default 0.6 m straight on), turns to face the door if
  ``face = true``, then reports its task accomplished
  (:data:`~cfgplan.runtime.ACHIEVED`). Its ``stop`` hook halts the robot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from cfgplan.runtime import ACHIEVED, ResourceFailure, current_robot, functionality
from cfgplan.sim import hardware
from cfgplan.sim.geometry import wrap
from cfgplan.sim.impl.control import clip, steer

Pos = tuple[float, float]
Image = dict[str, Any]

COMPASS_LIMIT = math.radians(15)
"""A compass this far off the odometry's heading is disturbed."""

CALIBRATION = 5
"""Readings the compass takes to learn its offset from the odometry."""

APPROACH = 0.8
"""Metres before the door where a crossing robot is on the door's axis."""

THROUGH = 0.45
"""Metres beyond the door where it heads for its target."""


@functionality("camera")
def camera() -> Image:
    return hardware().camera()


@functionality("compass")
def compass() -> float:
    """The heading; a reading inconsistent with the odometry fails the compass."""
    hw = hardware()
    reading = hw.compass()
    odometry = hw.odometry()[2]
    memory = hw.memory("compass")
    diff = wrap(reading - odometry)
    count = memory.get("count", 0)
    if count < CALIBRATION:
        # the mean offset over the first readings (on a circle)
        memory["sin"] = memory.get("sin", 0.0) + math.sin(diff)
        memory["cos"] = memory.get("cos", 0.0) + math.cos(diff)
        memory["offset"] = math.atan2(memory["sin"], memory["cos"])
        memory["count"] = count + 1
        return reading
    residual = wrap(diff - memory["offset"])
    if abs(residual) > COMPASS_LIMIT:
        raise ResourceFailure(
            f"compass reads {math.degrees(reading):.0f} deg, {math.degrees(residual):+.0f} deg "
            "off the odometry's heading: a magnetic disturbance"
        )
    memory["offset"] = wrap(memory["offset"] + 0.02 * residual)  # the odometry drifts slowly
    return reading


def _seen(image: Image, name: str, what: str, ranged: bool) -> list[Any] | None:
    """What the image says of ``name`` (``None``: nothing, noted; for
    :data:`~cfgplan.sim.onboard.MISSING` seconds running: a failure)."""
    sees = image.get("sees", {})
    found = sees.get(name) if isinstance(sees, dict) else None
    robot = current_robot()
    hw = hardware()
    instance = f"{what}({robot}, {name})"
    if found is None:
        hw.missing(instance, f"{name} is not in view of {robot}'s camera")
        return None
    if ranged and found[1] is None:
        hw.missing(instance, f"{name} is too near {robot}'s camera to measure its distance")
        return None
    hw.found(instance)
    return list(found)


@functionality("measure-door")
def measure_door(door: str, image: Image) -> tuple[Pos, float] | None:
    """The door's position and orientation (of its passage) relative to the observer."""
    seen = _seen(image, door, "measure-door", True)
    if seen is None or seen[2] is None:
        return None
    bearing, distance, orient = seen
    return (distance * math.cos(bearing), distance * math.sin(bearing)), orient


@functionality("measure-robot-pos")
def measure_robot_pos(robot: str, image: Image) -> Pos | None:
    seen = _seen(image, robot, "measure-robot-pos", True)
    if seen is None:
        return None
    bearing, distance, _ = seen
    return distance * math.cos(bearing), distance * math.sin(bearing)


@functionality("measure-robot-angle")
def measure_robot_angle(robot: str, image: Image) -> float | None:
    seen = _seen(image, robot, "measure-robot-angle", False)
    return None if seen is None else float(seen[0])


@functionality("measure-robot-orient-compass")
def measure_robot_orient_compass(robot: str, mine: float, theirs: float) -> float:
    return wrap(theirs - mine)


@functionality("measure-robot-orient-camera")
def measure_robot_orient_camera(robot: str, bearing_mine: float, bearing_theirs: float) -> float:
    return wrap(math.pi + bearing_mine - bearing_theirs)


@functionality("transform-info")
def transform_info(
    robot: str,
    door: str,
    robot_orient: float,
    robot_pos: Sequence[float],
    door_orient: float,
    door_pos: Sequence[float],
) -> tuple[float, Pos]:
    """The door's orientation and position relative to ``robot`` (:out order)."""
    dx, dy = door_pos[0] - robot_pos[0], door_pos[1] - robot_pos[1]
    c, s = math.cos(robot_orient), math.sin(robot_orient)
    return wrap(door_orient - robot_orient), (c * dx + s * dy, -s * dx + c * dy)


def _halt(door: str) -> None:
    hardware().halt()


@functionality("cross-door", stop=_halt)
def cross_door(door: str, pos: Sequence[float], orient: float) -> object:
    """Drive through ``door`` with its pose relative to the robot (module docstring)."""
    hw = hardware()
    memory = hw.memory(f"cross-door {door}")
    dx, dy = float(pos[0]), float(pos[1])
    nx, ny = math.cos(orient), math.sin(orient)
    if "sign" not in memory:  # pass the door away from the side the robot is on
        memory["sign"] = 1.0 if dx * nx + dy * ny > 0 else -1.0
        memory["phase"] = "approach"
    nx, ny = nx * memory["sign"], ny * memory["sign"]
    lx, ly = -ny, nx  # to the left of the passage

    def point(depth: float, left: float) -> Pos:
        return dx + depth * nx + left * lx, dy + depth * ny + left * ly

    depth = -(dx * nx + dy * ny)  # the robot's depth beyond the door
    settings = hw.params.get("cross-door", {})
    target = settings.get("target", [0.6, 0.0])
    top = float(settings.get("speed", 0.3))
    phase = memory["phase"]
    if phase == "approach" and depth >= THROUGH - 0.15:
        phase = memory["phase"] = "target"
    if phase == "approach":
        ax, ay = point(min(max(depth, -APPROACH) + 0.6, THROUGH), 0.0)
        hw.drive(*steer(ax, ay, top))
        return None
    if phase == "target":
        tx, ty = point(float(target[0]), float(target[1]))
        if math.hypot(tx, ty) > 0.08:
            hw.drive(*steer(tx, ty, top))
            return None
        phase = memory["phase"] = "face" if settings.get("face", False) else "done"
    if phase == "face":
        bearing = math.atan2(dy, dx)
        if abs(bearing) > math.radians(5):
            hw.drive(0.0, clip(1.5 * bearing, 0.8))
            return None
    hw.halt()
    memory.clear()
    return ACHIEVED
