"""Carry a bar (thesis 6.3, Appendix A.2) in the simulator.

* ``laser``, ``odometer``, ``sonar`` — the robot's sensors (a broken laser
  raises :class:`~cfgplan.runtime.ResourceFailure`: the laser fails, 6.3.2).
* ``meas-robot-angle-dist-laser`` — the other robot's bearing and distance
  from the echoes of its post (the bar's stand) in the scan.
* ``localize-sonar``, ``localize-laser`` — a global pose: the odometry moved
  on from the last estimate, corrected by matching the ranges to the map
  (:func:`cfgplan.sim.perception.localize`).
* ``meas-robot-angle-dist-localizer`` — bearing and distance from two global poses.
* ``calc-robot-speed-diff`` — how fast the distance changes: it keeps the last
  distance and its time ("a memory and access to a clock", 6.3.2).
* ``stalk-robot`` — the follower: turns towards the leader and keeps the
  bar's length (``params.carry.distance``, default 1.2 m) with the distance
  and its rate of change.
* ``lead-robot`` — the leader: follows its route (``params.carry.route``:
  points ``[forward, left]`` in metres from its start pose) by dead
  reckoning of its own commands, slows down when the follower falls behind
  and stops for it; at the route's end the bar is delivered
  (:data:`~cfgplan.runtime.ACHIEVED`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from cfgplan.runtime import ACHIEVED, current_robot, functionality
from cfgplan.sim import hardware
from cfgplan.sim.geometry import wrap
from cfgplan.sim.impl.control import clip, steer
from cfgplan.sim.perception import localize, runs

Scan = dict[str, Any]

BAR = 1.2
"""The bar's length the robots keep by default (metres)."""


@functionality("laser")
def laser() -> Scan:
    return hardware().laser()


@functionality("odometer")
def odometer() -> list[float]:
    return hardware().odometry()


@functionality("sonar")
def sonar() -> Scan:
    return hardware().sonar()


@functionality("meas-robot-angle-dist-laser")
def meas_robot_angle_dist_laser(other: str, scan: Scan) -> tuple[float, float] | None:
    """Bearing and distance of ``other``'s centre, from the echoes of its body."""
    hw = hardware()
    found = runs(scan, other)
    instance = f"meas-robot-angle-dist-laser({current_robot()}, {other})"
    if not found:
        hw.missing(instance, f"{other} is not in {current_robot()}'s laser scan")
        return None
    hw.found(instance)
    run = max(found, key=lambda r: len(r.points))
    x = sum(p[0] for p in run.points) / len(run.points)
    y = sum(p[1] for p in run.points) / len(run.points)
    near = math.hypot(x, y)
    # the echoes lie on the near half of the robot's round post: on average
    # pi/4 of its radius nearer than its centre
    distance = near + hw.knowledge.post * math.pi / 4
    return math.atan2(y, x), distance


def _localize(scan: Scan, odometry: Sequence[float]) -> list[float]:
    hw = hardware()
    memory = hw.memory("localize")
    odo = (float(odometry[0]), float(odometry[1]), float(odometry[2]))
    last = memory.get("estimate")
    if last is None:
        guess = odo
    else:
        # the odometry's motion since the last estimate, applied to that estimate
        lo = memory["odometry"]
        c, s = math.cos(lo[2]), math.sin(lo[2])
        fx = c * (odo[0] - lo[0]) + s * (odo[1] - lo[1])
        fy = -s * (odo[0] - lo[0]) + c * (odo[1] - lo[1])
        c, s = math.cos(last[2]), math.sin(last[2])
        guess = (
            last[0] + c * fx - s * fy,
            last[1] + s * fx + c * fy,
            wrap(last[2] + odo[2] - lo[2]),
        )
    estimate = localize(guess, scan, hw.knowledge.walls)
    memory["estimate"], memory["odometry"] = estimate, odo
    return list(estimate)


@functionality("localize-sonar")
def localize_sonar(odometry: Sequence[float], sonar: Scan) -> list[float]:
    return _localize(sonar, odometry)


@functionality("localize-laser")
def localize_laser(odometry: Sequence[float], scan: Scan) -> list[float]:
    return _localize(scan, odometry)


@functionality("meas-robot-angle-dist-localizer")
def meas_robot_angle_dist_localizer(
    other: str, mine: Sequence[float], theirs: Sequence[float]
) -> tuple[float, float]:
    dx, dy = theirs[0] - mine[0], theirs[1] - mine[1]
    return wrap(math.atan2(dy, dx) - mine[2]), math.hypot(dx, dy)


@functionality("calc-robot-speed-diff")
def calc_robot_speed_diff(other: str, dist: float) -> float:
    """How fast the distance to ``other`` changes (m/s, positive: growing), smoothed."""
    hw = hardware()
    memory = hw.memory(f"speed-diff {other}")
    now = hw.clock()
    rate = memory.get("rate", 0.0)
    if "dist" in memory and now > memory["t"]:
        rate = 0.5 * rate + 0.5 * (dist - memory["dist"]) / (now - memory["t"])
    memory.update(dist=dist, t=now, rate=rate)
    return float(rate)


def _carry(hw: Any) -> dict[str, Any]:
    found = hw.params.get("carry", {})
    return found if isinstance(found, dict) else {}


def _halt(*_: str) -> None:
    hardware().halt()


@functionality("stalk-robot", stop=_halt)
def stalk_robot(other: str, angle: float, dist: float, speed_diff: float) -> None:
    """Follow ``other`` at the bar's length."""
    hw = hardware()
    length = float(_carry(hw).get("distance", BAR))
    memory = hw.memory("stalk")
    speed = memory.get("speed", 0.0)
    # the leader's speed is about ours plus the rate at which the distance grows
    wanted = speed + speed_diff + 0.8 * (dist - length)
    speed = max(0.0, min(hw.max_speed, 0.5 * speed + 0.5 * wanted))
    memory["speed"] = speed
    hw.drive(speed * max(0.0, math.cos(angle)), clip(1.5 * angle, 1.0))


@functionality("lead-robot", stop=_halt)
def lead_robot(other: str, dist: float) -> object:
    """Lead along the route, at the pace the follower keeps (module docstring)."""
    hw = hardware()
    settings = _carry(hw)
    route = [tuple(map(float, p)) for p in settings.get("route", [])]
    length = float(settings.get("distance", BAR))
    top = float(settings.get("speed", 0.2))
    memory = hw.memory("lead")
    now = hw.clock()
    x, y, th = memory.get("pose", (0.0, 0.0, 0.0))
    if "t" in memory:  # dead reckoning of what it told its motors
        v, w = memory["command"]
        h = min(now - memory["t"], hw.watchdog)  # the motors stop after that
        x, y, th = (
            x + v * h * math.cos(th + w * h / 2),
            y + v * h * math.sin(th + w * h / 2),
            th + w * h,
        )
    if not route:
        hw.note(
            f"lead-robot({current_robot()}, {other})",
            f"{current_robot()} has no route to lead along (params.carry.route)",
        )
        hw.halt()
        return None
    leg = memory.get("leg", 0)
    while leg < len(route) and math.hypot(route[leg][0] - x, route[leg][1] - y) < 0.08:
        leg += 1
    memory.update(pose=(x, y, th), t=now, leg=leg)
    if leg >= len(route):
        memory["command"] = (0.0, 0.0)
        hw.halt()
        return ACHIEVED
    tx, ty = route[leg]
    c, s = math.cos(th), math.sin(th)
    v, w = steer(c * (tx - x) + s * (ty - y), -s * (tx - x) + c * (ty - y), top, 0.8)
    # the bar: slow down as the follower falls behind, wait for it beyond a margin
    slack = dist - length
    v *= max(0.0, min(1.0, 1.0 - slack / 0.12))
    memory["command"] = (v, w)
    hw.drive(v, w)
    return None
