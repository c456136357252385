"""What a laser saw when its functionality failed (build-a-wall, 6.4): the
scan at the failure, drawn on the trajectories.

In build-a-wall, Emil's ``measure-pos-laser(Emil, W1)`` fails because block
B1 hides the free end of wall W1 from Emil's laser, and Rasmus takes over.
At the moment of the failure this draws, from the robot's pose then, the
laser's beams, noise-free (the world's poses at that moment:
:class:`~cfgplan.sim.world.Sample`): in light red those that reach a built
wall; in brown those a block stops, continued dotted to the wall they would
have reached, where red squares mark what the block hid; and the blocks
where they were then, outlined in red.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Polygon

from cfgplan.sim.geometry import Scene, Segment, rectangle
from cfgplan.sim.world import Sample, World

__all__ = ["draw_laser_view", "laser_failures"]

BEAMS = 181
"""Beams drawn (every other of the default 361)."""


def laser_failures(world: World, records: list[tuple[float, str]]) -> list[tuple[float, str]]:
    """The failures (time, robot) of a functionality reading the robot's laser."""
    out = []
    for t, resource in records:
        name, _, args = resource.partition("(")
        robot = args.rstrip(")").split(",")[0].strip()
        if "laser" in name and robot in world.bodies and world.scenario.carries(robot, "laser"):
            out.append((t, robot))
    return out


def _scene(world: World, sample: Sample, blocks: bool) -> Scene:
    index = {name: i for i, name in enumerate(world.labels)}
    segments: list[tuple[Segment, int]] = [(s, 0) for s in world.segments]
    for name, wall in world.walls.items():
        corners = rectangle(*wall.at, math.radians(wall.heading), *wall.size)
        segments += [(s, index[name]) for s in corners]
    if blocks:
        for name, block in world.blocks.items():
            pose = sample.blocks[name]
            segments += [(s, index[name]) for s in rectangle(*pose, *block.spec.size)]
    return Scene.build(segments, [])


def draw_laser_view(
    ax: Axes, world: World, sample: Sample, robot: str
) -> tuple[list[tuple[float, float]], str]:
    """Draw ``robot``'s laser at ``sample`` (module docstring); the points of
    walls a block hid, and a line that says what hid what (empty: nothing)."""
    spec = world.scenario.sensor(robot, "laser")
    x, y, h = sample.robots[robot]
    fov = math.radians(spec.fov)
    angles = h - fov / 2 + fov * np.arange(BEAMS) / (BEAMS - 1)
    seen, hit = _scene(world, sample, True).cast(x, y, angles, spec.max_range)
    bare, bare_hit = _scene(world, sample, False).cast(x, y, angles, spec.max_range)
    blocks = {world.labels.index(n) for n in world.blocks}
    walls = {world.labels.index(n) for n in world.walls}
    hidden: list[tuple[float, float]] = []
    hiders: dict[str, set[str]] = {}
    for i, a in enumerate(angles):
        r, r0 = float(seen[i]), float(bare[i])
        c, d = math.cos(a), math.sin(a)
        if int(hit[i]) in walls:  # the laser sees the wall there
            ax.plot([x, x + r * c], [y, y + r * d], color="#e41a1c", lw=0.5, alpha=0.25, zorder=2)
        elif int(hit[i]) in blocks and int(bare_hit[i]) in walls:  # the block hides it
            hidden.append((x + r0 * c, y + r0 * d))
            wall = world.labels[int(bare_hit[i])]
            hiders.setdefault(wall, set()).add(world.labels[int(hit[i])])
            ax.plot([x, x + r * c], [y, y + r * d], color="#7a4f1d", lw=0.6, alpha=0.7, zorder=2)
            ax.plot(
                [x + r * c, x + r0 * c],
                [y + r * d, y + r0 * d],
                color="#d62728",
                lw=0.5,
                ls=":",
                alpha=0.6,
                zorder=2,
            )
            ax.plot(
                [x + r0 * c], [y + r0 * d], ls="none", marker="s", ms=3.5, color="#d62728", zorder=4
            )
    for name, block in world.blocks.items():
        corners = rectangle(*sample.blocks[name], *block.spec.size)
        ax.add_patch(
            Polygon(
                [c[:2] for c in corners],
                closed=True,
                fill=False,
                edgecolor="#d62728",
                lw=1.2,
                zorder=4,
            )
        )
    said = "; ".join(f"{', '.join(sorted(b))} hides {w}" for w, b in sorted(hiders.items()))
    return hidden, said
