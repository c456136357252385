"""Implementations for the carry-a-bar domain (thesis 6.3, Appendix A.2), in a simulated room.

Pippi leads and Emil follows, a bar between them (Fig. 6.7). Poses are
``(x, y, heading)`` in the room's frame: metres, radians, heading 0 along +x.
The room is a rectangle; its walls are what the sonars measure.

* ``laser`` returns a scan: the range and bearing of each robot within reach,
  in the scanning robot's frame; ``meas-robot-angle-dist-laser`` reads the
  angle and distance to the other robot off it (the 33 configuration, Fig. 6.8 top).
* ``odometer`` returns the pose the robot believes it has (dead reckoning);
  ``sonar`` the distances to the four walls; ``localize-sonar`` corrects the
  odometry's position with the walls (``localize-laser`` does the same with
  the laser's reach); ``meas-robot-angle-dist-localizer`` computes angle and
  distance from two global poses (the 45 configurations, Fig. 6.8 bottom).
* ``calc-robot-speed-diff`` keeps the last distance and its time (the
  functionality "has a memory and access to a clock", 6.3.2).
* ``stalk-robot`` and ``lead-robot`` record what they receive in
  :data:`FOLLOWED` and :data:`LED`.

Both configurations give the same angle and distance (0 rad, 1.5 m), so a
switch between them is seen only in the trace. Run::

    cfgplan run domains/carry-bar/domain.lisp domains/carry-bar/state-6.3.2.lisp \\
        --impl examples/carry-bar/impl.py --cycles 60 --inject 'fail laser(Emil) at cycle 20'
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

from cfgplan.runtime import current_robot, functionality

Pose = tuple[float, float, float]

ROOM = (0.0, 0.0, 10.0, 6.0)
"""The room: x from 0 to 10 m, y from 0 to 6 m."""

WORLD: dict[str, Pose] = {
    "Pippi": (5.0, 3.0, 0.0),
    "Emil": (3.5, 3.0, 0.0),
}
"""Pippi leads, Emil follows 1.5 m behind, both facing +x."""

DRIFT = (0.05, -0.03)
"""The odometry's error in x and y (metres): what localization corrects."""

LASER_RANGE = 8.0

FOLLOWED: list[tuple[str, str, float, float, float]] = []
"""What stalk-robot received: (robot, other, angle, distance, speed difference)."""

LED: list[tuple[str, str, float]] = []
"""What lead-robot received: (robot, other, distance)."""

_LAST: dict[tuple[str, str], tuple[float, float]] = {}  # calc-robot-speed-diff's memory


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _bearing(observer: Pose, x: float, y: float) -> tuple[float, float]:
    """Range and bearing of the point (x, y) seen from ``observer``."""
    dx, dy = x - observer[0], y - observer[1]
    return math.hypot(dx, dy), wrap(math.atan2(dy, dx) - observer[2])


@functionality("laser")
def laser() -> dict[str, object]:
    """A scan: ``{"robot": me, "hits": {other: [range, bearing]}}``."""
    me = current_robot()
    pose = WORLD[me]
    hits = {}
    for name, other in WORLD.items():
        if name != me:
            rng, bearing = _bearing(pose, other[0], other[1])
            if rng <= LASER_RANGE:
                hits[name] = [rng, bearing]
    return {"robot": me, "hits": hits}


@functionality("odometer")
def odometer() -> list[float]:
    """The pose dead reckoning gives: off by :data:`DRIFT`."""
    x, y, heading = WORLD[current_robot()]
    return [x + DRIFT[0], y + DRIFT[1], heading]


@functionality("sonar")
def sonar() -> list[float]:
    """Distances to the walls west, south, east, north (the robot faces +x)."""
    x, y, _ = WORLD[current_robot()]
    x0, y0, x1, y1 = ROOM
    return [x - x0, y - y0, x1 - x, y1 - y]


@functionality("meas-robot-angle-dist-laser")
def meas_robot_angle_dist_laser(other: str, scan: dict[str, object]) -> tuple[float, float] | None:
    """Angle and distance to ``other`` from the scan (None: not in reach)."""
    hits = scan["hits"]
    assert isinstance(hits, dict)
    found = hits.get(other)
    if found is None:
        return None
    rng, bearing = found
    return bearing, rng


@functionality("localize-sonar")
def localize_sonar(odometry: Sequence[float], walls: Sequence[float]) -> list[float]:
    """The global pose: position from the walls, heading from the odometry."""
    west, south, _, _ = walls
    return [ROOM[0] + west, ROOM[1] + south, odometry[2]]


@functionality("localize-laser")
def localize_laser(odometry: Sequence[float], scan: dict[str, object]) -> list[float]:
    """The global pose from the odometry, corrected by its known drift (the
    laser's match against the map, reduced to its result)."""
    return [odometry[0] - DRIFT[0], odometry[1] - DRIFT[1], odometry[2]]


@functionality("meas-robot-angle-dist-localizer")
def meas_robot_angle_dist_localizer(
    other: str, mine: Sequence[float], theirs: Sequence[float]
) -> tuple[float, float]:
    """Angle and distance to ``other`` from both global poses."""
    rng, bearing = _bearing((mine[0], mine[1], mine[2]), theirs[0], theirs[1])
    return bearing, rng


@functionality("calc-robot-speed-diff")
def calc_robot_speed_diff(other: str, dist: float) -> float:
    """How fast the distance changes (m/s; positive: the other pulls away)."""
    key = (current_robot(), other)
    now = time.monotonic()
    last = _LAST.get(key)
    _LAST[key] = (dist, now)
    if last is None or now <= last[1]:
        return 0.0
    return (dist - last[0]) / (now - last[1])


@functionality("stalk-robot")
def stalk_robot(other: str, angle: float, dist: float, speed_diff: float) -> None:
    """The follower's action: here it records what it would steer by."""
    FOLLOWED.append((current_robot(), other, angle, dist, speed_diff))


@functionality("lead-robot")
def lead_robot(other: str, dist: float) -> None:
    """The leader's action: here it records the distance to the follower."""
    LED.append((current_robot(), other, dist))
