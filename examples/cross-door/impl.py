"""Implementations for the cross-door domain (thesis 4.6, 5.4), in a simulated 2-D world.

Poses are ``(x, y, heading)`` in a world frame (metres, radians; heading 0
along +x, counter-clockwise positive, and north-aligned so that a compass
reads the world heading). A door's heading is the direction of passage.

* ``camera`` returns a synthetic image: what the robot sees within its field
  of view, in its own frame. A door shows its position and orientation; a
  robot (a round Magellan Pro) only its position, so its orientation must come
  from elsewhere: the compasses (cost 44) or the other robot's camera (47).
* ``measure-door`` / ``measure-robot-pos`` / ``measure-robot-angle`` read the image.
* ``compass`` gives the robot's global heading; ``measure-robot-orient-compass``
  the orientation of one robot relative to another from two headings.
* ``transform-info`` turns the door's pose seen by the observer and the crossing
  robot's pose seen by the observer into the door's pose relative to the
  crossing robot.
* ``cross-door`` records what it receives in :data:`RECEIVED`.

Run the cost-44 configuration with::

    cfgplan run domains/cross-door/domain.lisp domains/cross-door/state-6.2.2-step1.lisp \\
        --impl examples/cross-door/impl.py --cycles 3
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from cfgplan.runtime import current_robot, functionality

Pose = tuple[float, float, float]
Pos = tuple[float, float]
Sighting = tuple[float, float, float | None]  # x, y in the camera frame; orientation if visible
Image = dict[str, object]

WORLD: dict[str, Pose] = {
    "Emil": (0.0, -2.0, 0.3),
    "Pippi": (3.0, -2.5, 2.5),
    "Door1": (4.0, 0.0, math.pi / 2),
}
"""The true poses of the simulation (Fig. 4.2: Emil left, Pippi right, in Room1)."""

DOORS = {"Door1"}
FIELD_OF_VIEW = math.pi  # radians, centred on the heading
RANGE = 10.0  # metres

RECEIVED: list[tuple[str, str, Pos, float]] = []
"""What every cross-door call received: (robot, door, position, orientation)."""


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def relative(observer: Pose, target: Pose) -> Pose:
    """``target`` in the frame of ``observer``."""
    ox, oy, oh = observer
    dx, dy = target[0] - ox, target[1] - oy
    c, s = math.cos(oh), math.sin(oh)
    return (c * dx + s * dy, -s * dx + c * dy, wrap(target[2] - oh))


@functionality("camera")
def camera() -> Image:
    """What the running robot's camera sees, in its own frame."""
    me = current_robot()
    sees: dict[str, Sighting] = {}
    for name, pose in WORLD.items():
        if name == me:
            continue
        x, y, orient = relative(WORLD[me], pose)
        if math.hypot(x, y) <= RANGE and abs(math.atan2(y, x)) <= FIELD_OF_VIEW / 2:
            sees[name] = (x, y, orient if name in DOORS else None)
    return {"robot": me, "sees": sees}


def _sighting(image: Image, name: str) -> Sighting | None:
    sees = image["sees"]
    assert isinstance(sees, dict)
    found = sees.get(name)
    if not isinstance(found, tuple | list):  # a list when the image crossed a global channel
        return None
    x, y, orient = found
    return (x, y, orient)


@functionality("measure-door")
def measure_door(door: str, image: Image) -> tuple[Pos, float] | None:
    """The door's position and orientation relative to the observer (None: not in view)."""
    seen = _sighting(image, door)
    if seen is None or seen[2] is None:
        return None
    return (seen[0], seen[1]), seen[2]


@functionality("measure-robot-pos")
def measure_robot_pos(robot: str, image: Image) -> Pos | None:
    """The other robot's position relative to the observer."""
    seen = _sighting(image, robot)
    return None if seen is None else (seen[0], seen[1])


@functionality("measure-robot-angle")
def measure_robot_angle(robot: str, image: Image) -> float | None:
    """The bearing of the other robot in the observer's frame."""
    seen = _sighting(image, robot)
    return None if seen is None else math.atan2(seen[1], seen[0])


@functionality("compass")
def compass() -> float:
    """The running robot's global heading."""
    return WORLD[current_robot()][2]


@functionality("measure-robot-orient-compass")
def measure_robot_orient_compass(robot: str, mine: float, theirs: float) -> float:
    """The other robot's orientation relative to the observer, from two headings."""
    return wrap(theirs - mine)


@functionality("measure-robot-orient-camera")
def measure_robot_orient_camera(robot: str, bearing_mine: float, bearing_theirs: float) -> float:
    """The same from the bearings each robot measures to the other: pi + a1 - a2."""
    return wrap(math.pi + bearing_mine - bearing_theirs)


@functionality("transform-info")
def transform_info(
    robot: str,
    door: str,
    robot_orient: float,
    robot_pos: Pos,
    door_orient: float,
    door_pos: Pos,
) -> tuple[float, Pos]:
    """The door's orientation and position relative to ``robot`` (:out order),
    from both poses in the observer's frame (:in order of the domain)."""
    dx, dy = door_pos[0] - robot_pos[0], door_pos[1] - robot_pos[1]
    c, s = math.cos(robot_orient), math.sin(robot_orient)
    return wrap(door_orient - robot_orient), (c * dx + s * dy, -s * dx + c * dy)


@functionality("cross-door")
def cross_door(door: str, pos: Sequence[float], orient: float) -> None:
    """The action: here it only records the door's pose relative to the robot
    (``pos`` comes over a global channel, as JSON: a list)."""
    RECEIVED.append((current_robot(), door, (pos[0], pos[1]), orient))
