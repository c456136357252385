"""What a robot's sensors read off the world (6.1, 6.2.1): camera, compass,
laser, sonar, odometry. Each reading carries seeded noise; none carries a
true pose.

* **camera** — fixed on the robot (6.2.1): the bearing of each robot and
  door within its field of view and line of sight (walls and blocks hide
  things; robots do not, the markers stand above them), and their range —
  and a door's orientation, told by its coloured posts — only beyond
  ``min_range`` ("the cameras can only measure distances to objects further
  away than 2 meters").
* **compass** — the heading, off by the magnetic disturbances around.
* **laser** — a planar scan: range and what was hit (walls, blocks and robots
  are told apart by their reflectance marks) for each beam. The laser's
  plane is above the robots' bodies: of a robot it sees the post at its
  centre (the bar's stand, 6.3.1).
* **sonar** — the same with a few beams all around and shorter range, low
  on the body: it sees robots' bodies.
* **odometry** — the pose dead reckoning gives (:mod:`cfgplan.sim.bodies`).

A broken sensor, or one the robot does not carry, raises
:class:`~cfgplan.runtime.ResourceFailure`: the implementation that reads it
fails with it, and the monitor sees the resource fail (5.5).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from cfgplan.runtime.faults import ResourceFailure
from cfgplan.sim.geometry import relative, wrap

if TYPE_CHECKING:
    from cfgplan.sim.world import World

__all__ = ["camera", "compass", "deflection", "odometry", "scan"]


def _usable(world: World, robot: str, kind: str) -> None:
    body = world.bodies[robot]
    if not world.scenario.carries(robot, kind):  # type: ignore[arg-type]
        raise ResourceFailure(f"{robot} has no {kind}")
    if kind in body.broken:
        raise ResourceFailure(f"{robot}'s {kind} does not answer (broken)")


def deflection(world: World, x: float, y: float) -> float:
    """Radians a compass at (x, y) reads off, from the disturbances active now."""
    total = 0.0
    for m in world.magnetic:
        if world.time < m.start or (m.until is not None and world.time >= m.until):
            continue
        d2 = (x - m.at[0]) ** 2 + (y - m.at[1]) ** 2
        total += math.radians(m.deflection) * math.exp(-d2 / (2 * m.radius**2))
    return total


def compass(world: World, robot: str) -> float:
    _usable(world, robot, "compass")
    spec = world.scenario.sensor(robot, "compass")
    x, y, heading = world.bodies[robot].pose
    noise = world.rng(robot, "compass").gauss(0.0, math.radians(spec.noise))
    return wrap(heading + deflection(world, x, y) + noise)


def odometry(world: World, robot: str) -> list[float]:
    _usable(world, robot, "odometry")
    return list(world.bodies[robot].odometry)


def camera(world: World, robot: str) -> dict[str, Any]:
    """``{"sees": {name: [bearing, range or None, orientation or None]}}`` in
    the camera's frame (radians, metres); orientation for doors only."""
    _usable(world, robot, "camera")
    spec = world.scenario.sensor(robot, "camera")
    rng = world.rng(robot, "camera")
    pose = world.bodies[robot].pose
    scene = world.scene()
    seen: dict[str, list[float | None]] = {}
    targets: list[tuple[str, float, float, float | None]] = [
        (n, b.pose[0], b.pose[1], None) for n, b in world.bodies.items() if n != robot
    ]
    targets += [(n, d.at[0], d.at[1], math.radians(d.passage)) for n, d in world.doors.items()]
    for name, x, y, facing in targets:
        fx, fy = relative(pose, x, y)
        distance = math.hypot(fx, fy)
        bearing = math.atan2(fy, fx)
        if distance > spec.max_range or abs(bearing) > math.radians(spec.fov) / 2:
            continue
        ranges, _ = scene.cast(pose[0], pose[1], np.array([pose[2] + bearing]), distance)
        if ranges[0] < distance - 0.02:
            continue  # hidden behind a wall or a block
        measured_bearing = bearing + rng.gauss(0.0, math.radians(spec.bearing_noise))
        measured: list[float | None] = [measured_bearing, None, None]
        if distance >= spec.min_range:
            measured[1] = distance * (1 + rng.gauss(0.0, spec.range_noise))
            if facing is not None:
                measured[2] = wrap(
                    facing - pose[2] + rng.gauss(0.0, math.radians(spec.orient_noise))
                )
        seen[name] = measured
    return {"robot": robot, "sees": seen}


def scan(world: World, robot: str, kind: str) -> dict[str, Any]:
    """A laser or sonar scan in the robot's frame: beam ``i`` points at
    ``start + i * step`` radians; ``ranges[i]`` in metres (``max_range``: no
    echo), ``hits[i]`` what it hit (a name, ``"wall"`` for the building, or
    ``None``)."""
    _usable(world, robot, kind)
    spec = world.scenario.sensor(robot, kind)  # type: ignore[arg-type]
    rng = world.rng(robot, kind)
    pose = world.bodies[robot].pose
    if kind == "laser":
        fov = math.radians(spec.fov)
        start, step = -fov / 2, fov / (spec.beams - 1)
    else:  # all around, from straight behind, so that the front beams are consecutive
        start, step = -math.pi, 2 * math.pi / spec.beams
    angles = pose[2] + start + step * np.arange(spec.beams)
    motion = world.scenario.motion
    scene = world.scene(exclude=robot, robots=motion.post if kind == "laser" else motion.radius)
    # a ray starts at the robot's rim (its own body never echoes)
    ranges, labels = scene.cast(pose[0], pose[1], angles, spec.max_range)
    noise = np.array([rng.gauss(0.0, 1.0) for _ in range(spec.beams)])
    sigma = spec.noise if kind == "laser" else spec.noise + 0.01 * ranges
    echo = labels >= 0
    measured = np.where(echo, np.clip(ranges + noise * sigma, 0.0, spec.max_range), spec.max_range)
    names = world.labels
    return {
        "robot": robot,
        "start": start,
        "step": step,
        "max_range": spec.max_range,
        "ranges": [round(float(r), 4) for r in measured],
        "hits": [names[int(i)] if i >= 0 else None for i in labels],
    }
