"""Build a wall (thesis 6.4, Appendix A.3) in the simulator.

Orientations are those of an object's long faces' normal, in the observer's
frame, within a quarter turn of its heading (a block is symmetric); for a
built wall the normal of its face seen from the robots' side.

* ``laser``, ``sonar`` — the robot's range sensors.
* ``measure-orient-laser``, ``measure-orient-sonar`` — an object's orientation
  from its faces in the scan (:func:`cfgplan.sim.perception.block`; a robot
  pushing a block knows the face in front of it is a long side).
* ``measure-pos-laser`` — a block's centre (from a long side and the ends of
  it that are true corners, or a whole short side), or a built wall's corner
  at its free end.
  When something nearer hides that corner from the laser for :data:`HIDDEN`
  seconds running ("the block may occlude the wall so that the laser can
  not register the wall", 6.4), the measurement raises
  :class:`~cfgplan.runtime.ResourceFailure`: the monitor takes it as that
  functionality failing, and the society re-plans without it (Rasmus
  measures instead, Fig. 6.12). Any measurement without data for
  :data:`~cfgplan.sim.onboard.MISSING` seconds fails likewise.
* ``transform-block-data`` — the block's position and orientation relative
  to its slot at the wall's free end: ``[across, depth]`` (metres; across:
  to the right of the pushing direction, depth: negative while short of the
  slot) and the turn (radians, counter-clockwise).
* ``push-block`` — each pusher computes the motion the block should make
  (towards the slot's axis, straightening as it enters, slower near the end)
  and pushes its side of the back face accordingly (``params.push``, which
  the simulator sets for pushers: its side and offset), keeping itself square
  to the face with its own orientation to the block. When its measurements
  say the block is in the slot, aligned, the task is accomplished.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from cfgplan.runtime import ACHIEVED, current_robot, functionality
from cfgplan.sim import hardware
from cfgplan.sim.impl.control import clip
from cfgplan.sim.onboard import MISSING
from cfgplan.sim.perception import block, faces, free_end, long_face, runs, square

Scan = dict[str, Any]
Pos = tuple[float, float]

HIDDEN = 0.25
"""Seconds a wall's free end must stay hidden before its measurement fails."""

LOOKAHEAD = (0.3, 1.0)
"""Metres ahead on the slot's axis the block is steered towards: 0.6 of the
way left, within these bounds (gentle far away, firm near the wall)."""

TURN = 0.08
"""Radians per second a heavy block is turned at most."""

DONE = (0.015, 0.03, math.radians(2.0))
"""Depth left, distance across and turn (radians) within which a pusher
takes the block as aligned."""


@functionality("laser")
def laser() -> Scan:
    return hardware().laser()


@functionality("sonar")
def sonar() -> Scan:
    return hardware().sonar()


def _orientation(scan: Scan, name: str, what: str) -> float | None:
    """The normal of ``name``'s long sides in the robot's frame, squared (module docstring)."""
    hw = hardware()
    robot = current_robot()
    instance = f"{what}({robot}, {name})"
    k = hw.knowledge
    found = [r for r in runs(scan, name) if len(r.points) >= 3]
    if not found:
        hw.missing(instance, f"{name} is not in {robot}'s scan")
        return None
    if hw.params.get("push", {}).get("block") == name:
        # pushing it: the face in front is a long side
        face = max(
            faces(max(found, key=lambda r: len(r.points))), key=lambda f: f[2].length, default=None
        )
        normal = None if face is None else math.atan2(face[2].normal[1], face[2].normal[0])
        why = f"{name}'s face is not in {robot}'s scan"
    elif name in k.blocks:
        seen = block(scan, name, k.blocks[name])
        normal, why = seen.normal, seen.why
    elif name in k.built:
        face = long_face(max(found, key=lambda r: len(r.points)), float(k.built[name]["size"][1]))
        normal = None if face is None else math.atan2(face[2].normal[1], face[2].normal[0])
        why = f"no long side of {name} in {robot}'s scan"
    else:
        normal, why = None, f"{robot} knows no object {name}"
    if normal is None:
        hw.missing(instance, why)
        return None
    hw.found(instance)
    return square(normal)


@functionality("measure-orient-laser")
def measure_orient_laser(name: str, scan: Scan) -> float | None:
    return _orientation(scan, name, "measure-orient-laser")


@functionality("measure-orient-sonar")
def measure_orient_sonar(name: str, scan: Scan) -> float | None:
    return _orientation(scan, name, "measure-orient-sonar")


@functionality("measure-pos-laser")
def measure_pos_laser(name: str, scan: Scan) -> Pos | None:
    """A block's centre, or a built wall's free-end corner (module docstring)."""
    hw = hardware()
    robot = current_robot()
    instance = f"measure-pos-laser({robot}, {name})"
    k = hw.knowledge
    found: tuple[float, float] | str
    if name in k.blocks:
        seen = block(scan, name, k.blocks[name])
        found = seen.centre if seen.centre is not None else seen.why
    elif name in k.built:
        built = k.built[name]
        found = free_end(scan, name, float(built["size"][1]), str(built["free_end"]))
    else:
        found = f"{robot} knows no object {name}"
    if isinstance(found, str):
        # hidden behind something: the laser cannot register it (6.4)
        hidden = HIDDEN if "hidden" in found else MISSING
        hw.missing(instance, f"{robot}'s laser cannot register {name}: {found}", hidden)
        return None
    hw.found(instance)
    return found


@functionality("transform-block-data")
def transform_block_data(
    block: str,
    wall: str,
    block_pos: Sequence[float],
    block_orient: float,
    wall_pos: Sequence[float],
    wall_orient: float,
) -> tuple[list[float], float]:
    """The block relative to its slot at the wall (module docstring)."""
    k = hardware().knowledge
    length, thickness = k.blocks[block]
    built = k.built[wall]
    mx, my = math.cos(wall_orient), math.sin(wall_orient)
    fx, fy = (-my, mx) if built["free_end"] == "left" else (my, -mx)
    reach = float(built["gap"]) + length / 2
    sx = wall_pos[0] + fx * reach + mx * thickness / 2
    sy = wall_pos[1] + fy * reach + my * thickness / 2
    dx, dy = block_pos[0] - sx, block_pos[1] - sy
    across = dx * my - dy * mx  # to the right of the pushing direction
    depth = dx * mx + dy * my
    return [across, depth], square(block_orient - wall_orient)


def _halt(*_: str) -> None:
    hardware().halt()


@functionality("push-block", stop=_halt)
def push_block(block: str, wall: str, pos: Sequence[float], orient: float, mine: float) -> object:
    """Push this robot's side of ``block`` towards its slot at ``wall``."""
    hw = hardware()
    push = hw.params.get("push", {})
    across, depth = float(pos[0]), float(pos[1])
    remaining = -depth
    if remaining < DONE[0]:
        hw.halt()
        if abs(across) < DONE[1] and abs(orient) < DONE[2]:
            return ACHIEVED
        hw.note(
            f"push-block({current_robot()}, {block}, {wall})",
            f"{block} reached {wall} {across * 100:+.0f} cm across, "
            f"turned {math.degrees(orient):+.1f} deg",
        )
        return None
    # head for a point on the slot's axis ahead, straightening near the end
    ahead = max(LOOKAHEAD[0], min(LOOKAHEAD[1], 0.6 * remaining))
    wanted = clip(math.atan2(across, ahead), math.radians(25))
    wanted *= min(1.0, remaining / 0.15)
    speed = min(0.12, 0.4 * remaining + 0.03)
    contact = float(push.get("contact", 0.45))
    turn = clip(2.0 * (wanted - orient), min(TURN, (speed - 0.01) / contact))
    offset = contact if push.get("side") == "left" else -contact
    mine_speed = speed - turn * offset
    hw.drive(mine_speed / max(0.5, math.cos(mine)), turn + 1.0 * mine)
    return None
