"""``animation.gif`` (``cfgplan simulate --animate``): the run, frame by frame.

One frame every :data:`FRAME` simulated seconds: the map, each robot where
it is with its trajectory so far, the blocks and the bar, and the running
configuration's cost. Written with Pillow's GIF encoder, which matplotlib
already depends on: no system package is needed.
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from cfgplan.sim.drawing import bounds, draw_block, draw_map, draw_robot, figure, shades
from cfgplan.sim.run import Run

__all__ = ["FRAME", "animate"]

FRAME = 0.5
"""Simulated seconds between two frames."""


def animate(run: Run, path: Path) -> None:
    world = run.world
    x0, y0, x1, y1 = bounds(world)
    colour = shades(list(world.bodies))
    radius = world.scenario.motion.radius
    every = max(1, round(FRAME / world.scenario.step))
    samples = world.samples
    frames: list[Image.Image] = []
    for i in range(0, len(samples), every):
        sample = samples[i]
        fig = figure(4.5, 4.5 * (y1 - y0) / (x1 - x0) + 0.4)
        ax = fig.add_subplot()
        draw_map(ax, world)
        for name, block in world.blocks.items():
            draw_block(ax, sample.blocks[name], block.spec.size, final=True, label=name)
        if world.scenario.world.bar is not None:
            a, b = (sample.robots[n] for n in world.scenario.world.bar.robots)
            ax.plot([a[0], b[0]], [a[1], b[1]], color="#b5651d", lw=3, zorder=6)
        for name in world.bodies:
            trail = samples[: i + 1 : every]
            ax.plot(
                [s.robots[name][0] for s in trail],
                [s.robots[name][1] for s in trail],
                ls="none",
                marker="o",
                ms=1.8,
                color=colour[name],
                zorder=4,
            )
            draw_robot(ax, sample.robots[name], radius, colour[name], filled=True, label=name)
        running = [s for s in run.recorder.segments if s.start <= sample.t]
        cost = (
            f"cost {running[-1].config.cost:g}"
            if running and running[-1].config
            else "nothing runs"
        )
        ax.set_title(f"{sample.t:5.1f} s   {cost}", fontsize=9, family="monospace")
        fig.tight_layout()
        canvas = fig.canvas
        canvas.draw()
        width, height = canvas.get_width_height()
        rgba = bytes(canvas.buffer_rgba())  # type: ignore[attr-defined]
        frames.append(
            Image.frombytes("RGBA", (width, height), rgba).convert(
                "P", palette=Image.Palette.ADAPTIVE
            )
        )
    if frames:
        frames[0].save(
            path, save_all=True, append_images=frames[1:], duration=int(FRAME * 1000 / 2), loop=0
        )
