"""Blocks pushed by two robots, and walls they are aligned with (6.4).

A block is too heavy for one robot: it moves only while both of its
pushers push its back face (each pushes with its forward speed times the
cosine of its angle to the face's normal). Two pushes at two points of the
face make it move like a differential drive: forward at their mean, turning
by their difference over the distance between them. A block that would
overlap a wall, a built wall or a robot that is not pushing it jams (it
stays, its pushers' wheels slip). A pusher keeps its contact point; its
heading relative to the block changes with its own turning, and the
controller of ``push-block`` must keep it square to the face.

A built wall (W1) is a fixed row of blocks; the slot at its free end, ``gap``
away, is where a block is *aligned* with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cfgplan.sim.bodies import Attachment, Body
from cfgplan.sim.geometry import Pose, Segment, rectangle, wrap
from cfgplan.sim.scenario import Block, WallObject

if TYPE_CHECKING:
    from cfgplan.sim.world import World

__all__ = ["MAX_DELTA", "BlockState", "alignment", "pusher_pose", "slot"]

MAX_DELTA = math.radians(40)
"""A pusher turned further than this from the face's normal only slides along it."""


@dataclass
class BlockState:
    name: str
    spec: Block
    pose: Pose
    jams: int = 0
    jammed: bool = False

    def segments(self) -> list[Segment]:
        return rectangle(self.pose[0], self.pose[1], self.pose[2], *self.spec.size)


def pusher_pose(block: Pose, thickness: float, attachment: Attachment, radius: float) -> Pose:
    """Where a pusher stands: its front against the back face at its offset."""
    x, y, h = block
    back = (x - math.cos(h) * thickness / 2, y - math.sin(h) * thickness / 2)
    contact = (back[0] - math.sin(h) * attachment.offset, back[1] + math.cos(h) * attachment.offset)
    heading = h + attachment.delta
    return (
        contact[0] - radius * math.cos(heading),
        contact[1] - radius * math.sin(heading),
        wrap(heading),
    )


def attach(block: BlockState, bodies: dict[str, Body]) -> None:
    """Put the block's pushers against its back face."""
    for side, name in sorted(block.spec.pushers.items()):
        body = bodies[name]
        offset = block.spec.contact if side == "left" else -block.spec.contact
        body.attached = Attachment(block.name, side, offset)
        body.pose = body.odometry = pusher_pose(
            block.pose, block.spec.size[1], body.attached, body.radius
        )


def push(world: World, block: BlockState, h: float) -> None:
    """One step of ``h`` seconds of a block and its pushers."""
    pushers = [b for b in world.bodies.values() if b.attached and b.attached.block == block.name]
    moves = [(b, *b.executed(world.time, h)) for b in pushers]
    pushes = [
        (b, max(0.0, v) * math.cos(b.attached.delta) if b.attached else 0.0) for b, v, _ in moves
    ]
    v_b = w_b = 0.0
    if len(pushes) == 2 and all(p > 0.005 for _, p in pushes):
        (b1, p1), (b2, p2) = pushes
        assert b1.attached is not None and b2.attached is not None
        o1, o2 = b1.attached.offset, b2.attached.offset
        w_b = (p2 - p1) / (o1 - o2)
        v_b = p1 + w_b * o1
    x, y, th = block.pose
    moved = (
        x + v_b * h * math.cos(th + w_b * h / 2),
        y + v_b * h * math.sin(th + w_b * h / 2),
        wrap(th + w_b * h),
    )
    if (v_b or w_b) and world.collides_block(block, moved, pushers):
        if not block.jammed:
            block.jams += 1
        block.jammed = True
        moved, w_b = block.pose, 0.0
    elif v_b or w_b:
        block.jammed = False
    block.pose = moved
    for body, _, w in moves:
        assert body.attached is not None
        delta = body.attached.delta + (w - w_b) * h
        body.attached.delta = max(-MAX_DELTA, min(MAX_DELTA, delta))
        body.moved(body.pose, pusher_pose(moved, block.spec.size[1], body.attached, body.radius))


def slot(wall: WallObject, block: Block) -> Pose:
    """Where ``block`` is aligned with ``wall``: at its free end, ``gap`` away."""
    x, y = wall.at
    h = math.radians(wall.heading)
    along = (-math.sin(h), math.cos(h))  # to the left, seen along the heading
    sign = 1.0 if wall.free_end == "left" else -1.0
    reach = wall.size[0] / 2 + wall.gap + block.size[0] / 2
    depth = (wall.size[1] - block.size[1]) / 2  # flush with the wall's face
    return (
        x + sign * along[0] * reach - math.cos(h) * depth,
        y + sign * along[1] * reach - math.sin(h) * depth,
        h,
    )


def alignment(block: BlockState, wall: WallObject) -> tuple[float, float, float]:
    """How far ``block`` is from its slot at ``wall``: across (to the right
    of the pushing direction) and deep (negative: short of the slot), in
    metres, and turned (radians, counter-clockwise; a block is symmetric, so
    modulo half a turn)."""
    sx, sy, sh = slot(wall, block.spec)
    dx, dy = block.pose[0] - sx, block.pose[1] - sy
    across = dx * math.sin(sh) - dy * math.cos(sh)  # to the right of the pushing direction
    depth = dx * math.cos(sh) + dy * math.sin(sh)
    turn = wrap(block.pose[2] - sh)
    if turn > math.pi / 2:
        turn -= math.pi
    elif turn <= -math.pi / 2:
        turn += math.pi
    return across, depth, turn
